"""The report's provenance (reporting/provenance.py): files by hash and size, the
command, the versions and the date."""

from __future__ import annotations

import hashlib


def test_provenance_hashes_and_command(tmp_path):
    from blockid.reporting import collect_provenance

    path = tmp_path / "d.csv"
    path.write_bytes(b"t,u,y\n0,1,2\n")
    prov = collect_provenance([path, path], ["/usr/local/bin/blockid", "report", "d.csv"])
    assert prov.command == "blockid report d.csv"
    assert len(prov.files) == 1 and prov.files[0].size == 12
    assert prov.files[0].sha256 == hashlib.sha256(b"t,u,y\n0,1,2\n").hexdigest()
    assert {"blockid", "numpy", "scipy", "numba", "pandas", "python", "platform"} <= set(
        prov.versions
    )
    assert prov.date.endswith("+00:00")
