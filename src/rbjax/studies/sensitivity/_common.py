"""Small helpers shared by the local and global sensitivity modules."""

from __future__ import annotations


def _is_lfe(name: str) -> bool:
    """Whether an output name is an octave-band force exposure level ``lfe_<band>_dB``."""
    return name.startswith("lfe_")
