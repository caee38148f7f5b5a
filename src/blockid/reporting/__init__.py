"""Reports people can show: one self-contained HTML file per identification.

>>> from blockid.reporting import build_report, collect_provenance
"""

from blockid.reporting.provenance import DataFile, Provenance, collect_provenance, file_sha256
from blockid.reporting.report import build_report, write_report

__all__ = [
    "DataFile",
    "Provenance",
    "build_report",
    "collect_provenance",
    "file_sha256",
    "write_report",
]
