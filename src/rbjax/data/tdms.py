"""National Instruments TDMS force records: :func:`read_tdms` through ``npTDMS`` (an
optional extra, ``pip install 'rbjax[formats]'``).

Each channel of each group is a channel, named ``group/channel``; its ``wf_increment``
property gives the sampling rate, its ``unit_string`` (or ``NI_UnitDescription``) its unit.
A channel named like a time column (``time_s``, ``t``) is the time vector of its group's
channels when they have no ``wf_increment``.
"""

from __future__ import annotations

import numpy as np

from .channels import Channel, channel_recording, import_extra, pick_channel
from .columns import parse_column
from .errors import DataError
from .recording import MIN_SAMPLES, Recording
from .sources import as_source, existing_file

__all__ = ["read_tdms"]


def _channels(tdms_file) -> list[Channel]:
    out = []
    for group in tdms_file.groups():
        time = None
        members = []
        for c in group.channels():
            kind, scale = parse_column(c.name)
            data = np.asarray(c[:])
            if data.dtype.kind not in "iuf" or data.size < MIN_SAMPLES:
                continue
            if kind == "time":
                time = data.astype(np.float64) * scale
                continue
            props = c.properties
            dt = props.get("wf_increment")
            rate = 1.0 / float(dt) if dt else None
            unit = props.get("unit_string") or props.get("NI_UnitDescription")
            members.append(Channel(f"{group.name}/{c.name}", data, unit, rate))
        out += [m._replace(time_s=time) if m.rate_Hz is None else m for m in members]
    return out


def read_tdms(
    path,
    *,
    channel: int | str | None = None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a TDMS file (LabVIEW, NI DAQmx).

    Args:
        path: the .tdms file.
        channel: ``group/channel``, the channel's name alone when no other group has one
            of that name, or its number in the listing an error shows; needed when the file
            holds more than one channel.
        rate_Hz: sampling rate, Hz, needed when the channel has neither ``wf_increment``
            nor a time channel; checked against them otherwise (to 1e-4).
        calibration_N_per_FS: newtons per full scale for integer (unscaled) samples, or
            newtons per unit for a channel in another unit (V...).
        height_m: drop height, m; default from the file name (``hNNN``).
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Returns:
        The :class:`Recording` of the channel (``source`` the file's name).

    Raises:
        DataError: no file at ``path``, not a TDMS file, an unknown channel (the channels
            are listed), a missing or disagreeing rate, a missing calibration, clipping, too
            few samples.
        MissingFormatError: npTDMS is not installed (``pip install 'rbjax[formats]'``).
    """
    source = as_source(path)
    if existing_file(path).stat().st_size == 0:
        raise DataError(f"{source}: empty file")
    nptdms = import_extra("nptdms", "TDMS (.tdms) files")
    try:
        f = nptdms.TdmsFile.read(str(path))
    except (ValueError, KeyError, EOFError, OSError) as e:
        raise DataError(f"{source}: cannot read it as a TDMS file ({e})") from None
    ch = pick_channel(_channels(f), channel, source)
    return channel_recording(
        ch,
        source,
        rate_Hz=rate_Hz,
        calibration_N_per_FS=calibration_N_per_FS,
        height_m=height_m,
        lowpass_Hz=lowpass_Hz,
    )
