"""The emulated rubber-ball recordings shipped inside the package."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from .errors import DataError
from .loading import load
from .recording import Recording

__all__ = ["EXAMPLES_LOWPASS_HZ", "examples_dir", "load_examples"]

EXAMPLES_LOWPASS_HZ = 1250.0
"""Cutoff of the (declared) measuring chain of the shipped emulated recordings, Hz."""


def examples_dir() -> Path:
    """Folder of the emulated rubber-ball recordings shipped inside the package.

    ``hHHH_dN.csv`` (drop N from HHH cm, 0.1 s at 44.1 kHz) and
    ``raw_h100_two_impacts.wav`` (1.5 s, float32 newtons, two impacts); see the
    README.md in that folder.

    Returns:
        The folder's path.
    """
    here = Path(__file__).resolve().parents[1] / "examples" / "emulated-rubber-ball"
    try:
        p = Path(str(files("rbjax") / "examples" / "emulated-rubber-ball"))
    except Exception:  # pragma: no cover - zipped installs etc.
        return here
    return p if p.is_dir() else here


def load_examples(pattern: str = "h*.csv") -> list[Recording]:
    """The shipped example recordings matching ``pattern`` (default: the 30 CSV drops).

    Heights come from the file names; ``lowpass_Hz`` is set to the declared measuring
    chain cutoff of these files (1250 Hz, 4th-order causal).

    Args:
        pattern: a glob pattern of file names in :func:`examples_dir`.

    Returns:
        The matching recordings (raw, not conditioned), sorted by file name.

    Raises:
        DataError: no file matches ``pattern``, or a file cannot be read (see :func:`load`).
    """
    paths = sorted(examples_dir().glob(pattern))
    if not paths:
        raise DataError(f"no example file matches {pattern!r} in {examples_dir()}")
    return load(paths, lowpass_Hz=EXAMPLES_LOWPASS_HZ)
