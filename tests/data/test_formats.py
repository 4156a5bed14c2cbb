"""The files acquisition systems export (rbjax.data.read_mat, read_uff, read_tdms, load): each
written here by its own library (scipy.io, h5py, pyuff, npTDMS) from the same simulated drops
as a CSV, read back to the same samples, rate and height, and conditioned to the same fit input;
channels by name or number, units, calibration; the bad inputs named."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import scipy.io

import rbjax.data as D
from rbjax.fit import prepare_data

from synthetic_records import HEIGHTS_M, RATE_HZ, long_records, write_mat_v73, write_tdms, write_uff

N = 8820  # 0.2 s of each 1 s drop: the impact at 0.1 s and its surroundings


@pytest.fixture(scope="module")
def forces():
    return [f[:N] for f in long_records()[1]]


def write_csv(path, x):
    t = np.arange(x.size) / RATE_HZ
    path.write_text(
        "time_s,force_N\n"
        + "\n".join(f"{a!r},{b!r}" for a, b in zip(t.tolist(), x.tolist()))
        + "\n"
    )


WRITERS = {
    ".mat": lambda p, x: scipy.io.savemat(p, {"fs": RATE_HZ, "force_N": x}),
    ".h5.mat": lambda p, x: write_mat_v73(p, {"fs": RATE_HZ, "force_N": x}),
    ".uff": lambda p, x: write_uff(p, [("force", x, "N")]),
    ".tdms": lambda p, x: write_tdms(
        p, [("force", x, {"wf_increment": 1 / RATE_HZ, "unit_string": "N"})]
    ),
}


@pytest.mark.parametrize("suffix", list(WRITERS))
def test_each_format_gives_the_samples_and_the_fit_input_of_the_csv(tmp_path, forces, suffix):
    csv_dir, fmt_dir = tmp_path / "csv", tmp_path / "fmt"
    csv_dir.mkdir()
    fmt_dir.mkdir()
    for h, x in zip(HEIGHTS_M, forces):
        name = f"h{int(round(h * 100)):03d}"
        write_csv(csv_dir / f"{name}.csv", x)
        WRITERS[suffix](fmt_dir / f"{name}{suffix.replace('.h5', '')}", x)
    from_csv = D.load(csv_dir, lowpass_Hz=1250.0)
    from_fmt = D.load(fmt_dir, lowpass_Hz=1250.0)
    rtol = 1e-10 if suffix == ".uff" else 0.0  # UFF's ASCII keeps 12 significant digits
    for a, b in zip(from_csv, from_fmt):
        assert (b.height_m, b.rate_Hz) == (a.height_m, a.rate_Hz) == (b.height_m, RATE_HZ)
        np.testing.assert_allclose(b.force_N, a.force_N, rtol=rtol, atol=rtol * 2000)
    # the fit sees the same records: same samples, onsets, noise, hence the same fit
    fa, fb = prepare_data(from_csv), prepare_data(from_fmt)
    np.testing.assert_allclose(fb.force_N, fa.force_N, rtol=0, atol=max(rtol * 2000, 1e-12))
    np.testing.assert_allclose(fb.onset_s, fa.onset_s, atol=1e-12)
    np.testing.assert_allclose(fb.noise_rms_N, fa.noise_rms_N, rtol=1e-6)


def test_channels_by_name_or_number_units_and_calibration(tmp_path, forces):
    x = forces[4]
    p = tmp_path / "h100.tdms"
    write_tdms(
        p,
        [
            ("force", x / 1e3, {"wf_increment": 1 / RATE_HZ, "unit_string": "kN"}),
            ("amplifier", x / 500.0, {"wf_increment": 1 / RATE_HZ, "unit_string": "V"}),
            ("raw", np.round(x / 5000.0 * 32768).astype(np.int16), {"wf_increment": 1 / RATE_HZ}),
        ],
    )
    with pytest.raises(
        D.DataError,
        match=(
            r"3 channels \(0: 'plate/force', 1: 'plate/amplifier', 2: 'plate/raw'\): pass channel="
        ),
    ):
        D.read_tdms(p)
    with pytest.raises(
        D.DataError, match=r"channel='accel' is not among the channels \(0: 'plate/force'"
    ):
        D.read_tdms(p, channel="accel")
    np.testing.assert_allclose(D.read_tdms(p, channel="force").force_N, x, rtol=1e-15)  # kN -> N
    np.testing.assert_array_equal(
        D.read_tdms(p, channel=0).force_N, D.read_tdms(p, channel="plate/force").force_N
    )
    with pytest.raises(
        D.DataError, match=r"is in 'V': pass calibration_N_per_FS= \(newtons per V\)"
    ):
        D.read_tdms(p, channel="amplifier")
    np.testing.assert_allclose(
        D.read_tdms(p, channel="amplifier", calibration_N_per_FS=500.0).force_N, x, rtol=1e-15
    )
    with pytest.raises(
        D.DataError, match="integer samples in channel 'plate/raw': pass calibration_N_per_FS="
    ):
        D.read_tdms(p, channel="raw")
    raw = D.read_tdms(p, channel="raw", calibration_N_per_FS=5000.0)
    np.testing.assert_allclose(raw.force_N, x, atol=0.5 * 5000.0 / 32768 * (1 + 1e-9))
    # the manifest names the channel and the calibration of each file, of any format
    m = tmp_path / "manifest.csv"
    m.write_text("file,height_m,channel,calibration_N_per_FS\nh100.tdms,1.0,amplifier,500\n")
    (rec,) = D.load(p, manifest=m)
    np.testing.assert_allclose(rec.force_N, x, rtol=1e-15)


def test_mat_files_name_their_channels_and_time_base(tmp_path, forces):
    x = forces[4]
    p = tmp_path / "h100.mat"
    t = np.arange(x.size) / RATE_HZ
    scipy.io.savemat(p, {"data": np.column_stack([x, 2 * x]), "time_s": t})
    with pytest.raises(D.DataError, match=r"2 channels \(0: 'data\(:,1\)', 1: 'data\(:,2\)'\)"):
        D.read_mat(p)
    rec = D.read_mat(p, channel="data(:,2)")
    assert rec.rate_Hz == RATE_HZ  # from the time vector
    np.testing.assert_array_equal(rec.force_N, 2 * x)
    scipy.io.savemat(p, {"s": {"F_kN": x / 1e3}})  # a struct, a unit in the name, no time base
    with pytest.raises(
        D.DataError, match="gives no sampling rate for channel 's.F_kN': pass rate_Hz="
    ):
        D.read_mat(p)
    np.testing.assert_allclose(D.read_mat(p, rate_Hz=RATE_HZ).force_N, x, rtol=1e-15)
    write_mat_v73(p, {"dt": 1 / RATE_HZ, "force_N": x})
    assert D.read_mat(p).rate_Hz == RATE_HZ


def test_uff_channels_and_units(tmp_path, forces):
    x = forces[4]
    p = tmp_path / "h100.uff"
    write_uff(p, [("plate force", x, "N"), ("plate voltage", x / 400.0, "V")])
    with pytest.raises(D.DataError, match=r"0: 'plate force', 1: 'plate voltage'"):
        D.read_uff(p)
    np.testing.assert_allclose(
        D.read_uff(p, channel="plate voltage", calibration_N_per_FS=400.0).force_N, x, rtol=1e-10
    )
    rec = D.read_uff(p, channel=0)
    assert rec.rate_Hz == RATE_HZ and any("read as 44100 Hz" in n for n in rec.notes)


def test_bad_files_and_missing_extras_are_named(tmp_path, forces, monkeypatch):
    x = forces[4]
    bad = tmp_path / "h100.xyz"
    bad.write_text("1,2\n")
    with pytest.raises(
        D.DataError,
        match=r"unknown file type '\.xyz': none of the known formats \(\*\.csv, .*\*\.tdms\)",
    ):
        D.load(bad)
    for suffix, what in (
        (".mat", "MATLAB .mat"),
        (".uff", "Universal File Format"),
        (".tdms", "TDMS"),
    ):
        p = tmp_path / f"h100{suffix}"
        p.write_bytes(b"this is not what the name says\n" * 10)
        with pytest.raises(D.DataError, match=f"h100{suffix}: .*{what}"):
            D.load(p, rate_Hz=RATE_HZ)
    # an optional reader that is not installed: the extra to install is named
    real = importlib.import_module

    def without(name, *args):
        if name in ("pyuff", "nptdms", "h5py"):
            raise ImportError(name)
        return real(name, *args)

    monkeypatch.setattr(importlib, "import_module", without)
    write_tdms(tmp_path / "h100.tdms", [("force", x, {"wf_increment": 1 / RATE_HZ})])
    with pytest.raises(
        D.MissingFormatError,
        match=(
            r"reading TDMS \(\.tdms\) files needs the package 'nptdms'.*pip install "
            r"'rbjax\[formats\]'"
        ),
    ):
        D.read_tdms(tmp_path / "h100.tdms")
