"""What conditioning did to a record, in words: :func:`describe_conditioning` turns the
entries of ``Recording.log`` (:func:`~rbjax.data.clean`, :func:`~rbjax.data.condition`)
into one line of a report."""

from __future__ import annotations

__all__ = ["describe_conditioning"]


def describe_conditioning(log: dict) -> str:
    """One line: rate, polarity, offset, drift, hum, the impact kept and the others cut.

    Args:
        log: ``Recording.conditioning`` (or the same dict with ``rate_Hz`` added); steps
            absent from it are left out of the line.

    Returns:
        The steps in words, joined by ``"; "`` (empty if none is logged).
    """
    parts = []
    if log.get("rate_Hz") is not None:
        parts.append(f"{log['rate_Hz']:g} Hz")
    if "polarity" in log:
        parts.append(
            "sign "
            + ("flipped (recorded inverted)" if log["polarity"] != "as recorded" else "as recorded")
        )
    if log.get("offset_N") is not None:
        parts.append(f"offset {log['offset_N']:+.3g} N removed")
    if log.get("drift_N_per_s") is not None:
        parts.append(f"drift {log['drift_N_per_s']:+.3g} N/s removed")
    if log.get("hum"):
        parts.append(
            f"hum {log['hum']['frequency_Hz']:.2f} Hz ({log['hum']['amplitude_N']:.3g} N) removed"
        )
    if log.get("impact_s") is not None:
        parts.append(f"impact at {log['impact_s']:.4f} s kept")
    for other in log.get("further_impacts") or ():
        parts.append(
            f"further impact at {other['time_s']:.4f} s ({other['peak_N']:.4g} N: a rebound?) cut"
        )
    return "; ".join(parts)
