"""Recommended record lengths of the TESTU/TESTA identification (MAC050–141 manual 4.4.9,
4.4.10; :mod:`tuning.autotune`), in a module of their own so that the command line's help
names them without loading the numerics."""

from __future__ import annotations

__all__ = ["RECOMMENDED_COIL_SAMPLES", "RECOMMENDED_MECH_SAMPLES", "RECOMMENDED_TESTA_REPEATS"]

RECOMMENDED_COIL_SAMPLES: int = 64  #: TESTU samples (8.2 ms ≈ 8 coil time constants)
RECOMMENDED_MECH_SAMPLES: int = 64  #: TESTA samples per level (123 ms)
RECOMMENDED_TESTA_REPEATS: int = 4  #: repetitions of the two-level TESTA pair (8 records)
