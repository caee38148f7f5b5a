"""Experiment design: excitation signals for identification, and their properties.

Random-phase and odd random-phase multisines (:func:`multisine`), PRBS (:func:`prbs`) and
random binary signals (:func:`random_binary`); each returns an :class:`Excitation`,
whose excited lines, RMS value and crest factor are measured on its samples. The names
are imported on first use (PEP 562): :mod:`blockid.design.checks` checks a design
without loading NumPy, so the command line refuses a bad one at once.
"""

from __future__ import annotations

from blockid._lazy import lazy_names

#: Public name -> module that defines it.
_WHERE = {
    "Excitation": "blockid.design.excitation",
    "crest_factor": "blockid.design.excitation",
    "msequence": "blockid.design.binary",
    "multisine": "blockid.design.multisines",
    "multisine_lines": "blockid.design.multisines",
    "prbs": "blockid.design.binary",
    "random_binary": "blockid.design.binary",
}

__all__, __getattr__, __dir__ = lazy_names(__name__, _WHERE)
