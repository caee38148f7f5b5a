"""Input/output data: records, file reading and atomic writing, sample ranges.

The names are imported on first use (PEP 562): ``blockid.data.files`` and
``blockid.data.ranges`` check paths and ranges without loading NumPy or pandas, so the
command line can refuse bad arguments before it pays for them.
"""

from __future__ import annotations

from blockid._lazy import lazy_names

#: Public name -> module that defines it.
_WHERE = {
    "Dataset": "blockid.data.dataset",
    "Experiment": "blockid.data.dataset",
    "READ_SUFFIXES": "blockid.data.files",
    "WRITE_SUFFIXES": "blockid.data.files",
    "check_data_paths": "blockid.data.files",
    "check_disjoint": "blockid.data.ranges",
    "parse_range": "blockid.data.ranges",
    "read_data": "blockid.data.io",
    "write_table": "blockid.data.io",
    "write_text_atomic": "blockid.data.io",
}

__all__, __getattr__, __dir__ = lazy_names(__name__, _WHERE)
