"""Input/output data: records, file reading and atomic writing, sample ranges."""

from blockid.data.dataset import Dataset, Experiment
from blockid.data.io import READ_SUFFIXES, WRITE_SUFFIXES, read_data, write_table, write_text_atomic
from blockid.data.ranges import check_disjoint, parse_range

__all__ = [
    "Dataset",
    "Experiment",
    "READ_SUFFIXES",
    "WRITE_SUFFIXES",
    "check_disjoint",
    "parse_range",
    "read_data",
    "write_table",
    "write_text_atomic",
]
