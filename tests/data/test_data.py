"""Reading, checking, conditioning and averaging force-plate recordings (rbjax.data),
and the JAX causal filter of the fit (rbjax.spectrum.filters.sosfilt_jax), checked against SciPy."""

from __future__ import annotations

import dataclasses
import re
import struct
import wave

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.io.wavfile
import scipy.signal

import rbjax  # noqa: F401  (float64)
from rbjax import data as D
from rbjax.data import DataError, DataWarning
from rbjax.spectrum.filters import butter_lowpass_sos, lowpass_np, sosfilt_jax

RATE = 44100
NOISE_N = 0.8

# --------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------


def pulse_N(t_s, t0_s=0.0, peak_N=500.0, T_s=0.02):
    """Half-sine contact pulse of duration T_s starting at t0_s."""
    tau = np.asarray(t_s) - t0_s
    return np.where(
        (tau > 0) & (tau < T_s), peak_N * np.sin(np.pi * np.clip(tau, 0, T_s) / T_s), 0.0
    )


def smooth_pulse_N(t_s, t0_s, peak_N=500.0, T_s=0.002):
    """A*(u^3) exp(3(1-u)), u = (t-t0)/T: C2 at the start, peak A at t0+T."""
    u = np.clip((np.asarray(t_s) - t0_s) / T_s, 0, None)
    return peak_N * u**3 * np.exp(3 * (1 - u))


def raw_force(n=4410, onset=600, peak_N=500.0, noise_N=NOISE_N, seed=0, T_s=0.02):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    x = lowpass_np(pulse_N(t, onset / RATE, peak_N, T_s), 1250.0, RATE)
    return x + noise_N * rng.standard_normal(n)


def write_csv(path, force, rate=RATE, header="time_s,force_N", time=True, decimals=7):
    lines = [header] if header else []
    for i, f in enumerate(force):
        lines.append(f"{i / rate:.{decimals}f},{f:.3f}" if time else f"{f:.3f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def wav_bytes(payload: bytes, *, tag, bits, rate=RATE, channels=1, extensible=False, fact=True):
    block = channels * bits // 8
    if extensible:
        guid = struct.pack("<H", tag) + b"\x00\x00\x00\x00\x10\x00\x80\x00\x00\xaa\x00\x38\x9b\x71"
        fmt = struct.pack("<HHIIHH", 0xFFFE, channels, rate, rate * block, block, bits)
        fmt += struct.pack("<HHI", 22, bits, 0) + guid
    else:
        fmt = struct.pack("<HHIIHHH", tag, channels, rate, rate * block, block, bits, 0)
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt
    if fact:
        body += b"fact" + struct.pack("<II", 4, len(payload) // block)
    body += b"data" + struct.pack("<I", len(payload)) + payload
    return b"RIFF" + struct.pack("<I", len(body)) + body


# --------------------------------------------------------------------------------------
# filters
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 3, 4, 6])
def test_sosfilt_jax_matches_scipy_batched(order):
    sos = butter_lowpass_sos(order, 1250.0, RATE)
    x = np.random.default_rng(1).standard_normal((3, 2, 700)) * 100
    y_ref = scipy.signal.sosfilt(sos, x)
    y_j = jax.jit(sosfilt_jax)(sos, x)
    assert y_j.dtype == jnp.float64 and y_j.shape == x.shape
    np.testing.assert_allclose(np.asarray(y_j), y_ref, rtol=0, atol=1e-10)
    y_v = jax.vmap(lambda r: sosfilt_jax(sos, r))(x.reshape(6, 700))
    np.testing.assert_allclose(np.asarray(y_v), y_ref.reshape(6, 700), rtol=0, atol=1e-10)


def test_sosfilt_jax_gradient_is_the_adjoint_filter():
    # y = H x is linear and causal: d<w, Hx>/dx = H^T w = reverse(filter(reverse(w)))
    sos = butter_lowpass_sos(4, 1250.0, RATE)
    rng = np.random.default_rng(2)
    x, w = rng.standard_normal(400), rng.standard_normal(400)
    g = jax.grad(lambda v: jnp.sum(jnp.asarray(w) * sosfilt_jax(sos, v)))(jnp.asarray(x))
    np.testing.assert_allclose(np.asarray(g), scipy.signal.sosfilt(sos, w[::-1])[::-1], atol=1e-10)


@pytest.mark.parametrize("order", range(1, 11))
def test_butter_sections_are_scipys_bit_for_bit(order):
    # over the whole band, where zpk2sos's pairing of an odd order's zero at 0 changes
    ratios = np.concatenate([np.linspace(5e-4, 0.4995, 120), [1250.0 / RATE, 1250.0 / 48000]])
    for rate in (RATE, 48000.0):
        for cutoff in ratios * rate:
            ours = butter_lowpass_sos(order, cutoff, rate)
            ref = scipy.signal.butter(order, cutoff, fs=rate, output="sos")
            assert np.array_equal(ours, ref), (order, cutoff, rate, ours - ref)


def test_butter_rejects_bad_arguments():
    with pytest.raises(ValueError, match="cutoff_Hz"):
        butter_lowpass_sos(4, 30000.0, RATE)
    with pytest.raises(ValueError, match="order"):
        butter_lowpass_sos(0, 100.0, RATE)


# --------------------------------------------------------------------------------------
# shipped examples
# --------------------------------------------------------------------------------------


def test_examples_dir_ships_all_files():
    d = D.examples_dir()
    assert (d / "README.md").is_file()
    assert len(sorted(d.glob("h*_d*.csv"))) == 30
    assert (d / "raw_h100_two_impacts.wav").is_file()


def test_load_examples_csv_heights_and_rate():
    recs = D.load(sorted(D.examples_dir().glob("*.csv")))
    assert len(recs) == 30
    assert {r.rate_Hz for r in recs} == {44100.0}
    assert {r.n_samples for r in recs} == {4410}
    heights = sorted({r.height_m for r in recs})
    assert heights == pytest.approx([0.1, 0.2, 0.4, 0.8, 1.0, 1.6])
    for r in recs:
        assert r.height_m == pytest.approx(int(r.source[1:4]) / 100)
        assert 0.6 < r.noise_rms_N < 1.0
        assert r.time_s[1] == pytest.approx(1 / 44100)
    ex = D.load_examples()
    assert len(ex) == 30 and all(r.lowpass_Hz == 1250.0 for r in ex)


def test_load_directory_expands_sorted():
    recs = D.load(D.examples_dir())
    names = [r.source for r in recs]
    assert len(recs) == 31 and names == sorted(names)
    wav = recs[-1]
    assert wav.source == "raw_h100_two_impacts.wav" and wav.height_m == 1.0
    _, ref = scipy.io.wavfile.read(D.examples_dir() / "raw_h100_two_impacts.wav")
    np.testing.assert_array_equal(wav.force_N, ref.astype(np.float64))


def test_condition_examples_line_up_and_are_physical():
    peaks = {}
    for r in D.load_examples():
        c = D.condition(r)
        assert c.onset_s == 0.002 and c.n_samples == round(0.05 * RATE)
        assert c.lowpass_Hz == 1250.0
        start, end = c.contact_window()
        assert start == pytest.approx(
            0.002, abs=0.3 / RATE
        )  # re-located after the shift, with noise
        assert 0.0185 < end - start < 0.0215
        assert abs(np.mean(c.force_N[:60])) < 0.5  # baseline removed
        peaks.setdefault(r.height_m, []).append(c.peak_N)
    means = [np.mean(peaks[h]) for h in sorted(peaks)]
    assert np.all(np.diff(means) > 0) and 450 < means[0] < 500 and 1850 < means[-1] < 1900


def test_wav_two_impacts_first_kept_with_warning():
    r = D.read_wav(D.examples_dir() / "raw_h100_two_impacts.wav")
    assert r.rate_Hz == 44100.0 and r.n_samples == 66150 and r.height_m == 1.0
    imps = D.find_impacts(r.force_N, r.rate_Hz)
    assert len(imps) == 2
    gap_s = (imps[1].start_index - imps[0].start_index) / r.rate_Hz
    assert 0.6 < gap_s < 0.8
    assert imps[0].peak_N > imps[1].peak_N > 500
    with pytest.warns(DataWarning, match=r"raw_h100_two_impacts\.wav: 1 further impact.*0\.7"):
        c = D.condition(r)
    assert any("further impact" in n for n in c.notes)
    assert c.peak_N == pytest.approx(imps[0].peak_N, rel=0.01)
    # the second one on request
    with pytest.warns(DataWarning):
        c2 = D.condition(r, which="last")
    assert c2.peak_N == pytest.approx(imps[1].peak_N, rel=0.01)


# --------------------------------------------------------------------------------------
# readers
# --------------------------------------------------------------------------------------


def test_csv_header_variants_units_and_single_column(tmp_path):
    x = raw_force()
    a = D.read_csv(write_csv(tmp_path / "a.csv", x, header="Time,F"), height_m=0.5)
    (tmp_path / "b.csv").write_text(
        "t;Force\n" + "".join(f"{i / RATE:.7f};{f:.3f}\n" for i, f in enumerate(x))
    )
    b = D.read_csv(tmp_path / "b.csv")
    assert a.rate_Hz == b.rate_Hz == 44100.0 and a.height_m == 0.5 and b.height_m is None
    np.testing.assert_allclose(a.force_N, np.round(x, 3))
    # units in the header are applied
    lines = ["time [ms],force_kN"] + [
        f"{1e3 * i / RATE:.5f},{f / 1e3:.6f}" for i, f in enumerate(x)
    ]
    (tmp_path / "c.csv").write_text("\n".join(lines))
    c = D.read_csv(tmp_path / "c.csv")
    assert c.rate_Hz == 44100.0
    np.testing.assert_allclose(c.force_N, x, atol=1e-3)
    # one force column: rate needed
    p = write_csv(tmp_path / "h020_x.csv", x, header="force_N", time=False)
    r = D.read_csv(p, rate_Hz=RATE)
    assert r.rate_Hz == RATE and r.height_m == 0.2
    with pytest.raises(DataError, match=r"h020_x\.csv: no time column"):
        D.read_csv(p)
    with pytest.raises(DataError, match="disagrees"):
        D.read_csv(tmp_path / "a.csv", rate_Hz=48000)


def test_int_wav_with_calibration(tmp_path):
    x = raw_force(peak_N=1500.0)
    cal = 4000.0  # N per full scale
    for width in (1, 2, 3, 4):
        fs = 2 ** (8 * width - 1)
        codes = np.round(x / cal * fs).astype(np.int64)
        if width == 1:  # 8-bit PCM is unsigned
            payload = (codes + 128).astype(np.uint8).tobytes()
        elif width in (2, 4):
            payload = codes.astype(f"<i{width}").tobytes()
        else:
            b = (codes & 0xFFFFFF).astype("<u4").tobytes()
            payload = b"".join(b[i : i + 3] for i in range(0, len(b), 4))
        p = tmp_path / f"h100_int{width}.wav"
        with wave.open(str(p), "wb") as w:
            w.setnchannels(1)
            w.setsampwidth(width)
            w.setframerate(RATE)
            w.writeframes(payload)
        r = D.read_wav(p, calibration_N_per_FS=cal)
        assert r.rate_Hz == RATE and r.height_m == 1.0 and r.calibration_N_per_FS == cal
        np.testing.assert_allclose(r.force_N, codes / fs * cal, rtol=0, atol=1e-12)
        np.testing.assert_allclose(r.force_N, x, atol=cal / fs)
        with pytest.raises(
            DataError, match=rf"h100_int{width}\.wav: integer PCM.*calibration_N_per_FS"
        ):
            D.read_wav(p)
    # WAVE_FORMAT_EXTENSIBLE integer PCM (the stdlib wave of Python 3.11 refuses it)
    codes = np.round(x / cal * 32768).astype("<i2")
    p = tmp_path / "ext.wav"
    p.write_bytes(wav_bytes(codes.tobytes(), tag=1, bits=16, extensible=True, fact=False))
    np.testing.assert_allclose(D.read_wav(p, calibration_N_per_FS=cal).force_N, codes / 32768 * cal)


def test_float_wav_round_trip(tmp_path):
    x = raw_force().astype(np.float32)
    for ext in (False, True):
        p = tmp_path / f"float_{ext}.wav"
        p.write_bytes(wav_bytes(x.astype("<f4").tobytes(), tag=3, bits=32, extensible=ext))
        r = D.read_wav(p, height_m=0.4)
        assert r.rate_Hz == RATE and r.height_m == 0.4 and r.force_N.dtype == np.float64
        np.testing.assert_array_equal(r.force_N, x.astype(np.float64))
    # a chunk the reader does not know (a recorder's "bext") is skipped, with a note
    blob = wav_bytes(x.astype("<f4").tobytes(), tag=3, bits=32, fact=False)
    i = blob.index(b"data")
    extra = b"bext" + struct.pack("<I", 4) + b"abcd"
    p = tmp_path / "bext.wav"
    p.write_bytes(
        b"RIFF" + struct.pack("<I", len(blob) - 8 + len(extra)) + blob[8:i] + extra + blob[i:]
    )
    r = D.read_wav(p)
    np.testing.assert_array_equal(r.force_N, x.astype(np.float64))
    assert any("not understood" in n for n in r.notes)
    # float64, two channels, calibration in N per full scale
    y = np.stack([x.astype(np.float64) / 2000.0, np.zeros(x.size)], axis=1).astype("<f8")
    p = tmp_path / "stereo.wav"
    p.write_bytes(wav_bytes(y.tobytes(), tag=3, bits=64, channels=2))
    with pytest.raises(DataError, match="stereo.wav: 2 channels"):
        D.read_wav(p)
    r = D.read_wav(p, channel=0, calibration_N_per_FS=2000.0)
    np.testing.assert_allclose(r.force_N, x, rtol=1e-12)


def test_npy_reader(tmp_path):
    x = raw_force()
    p = tmp_path / "h040_a.npy"
    np.save(p, x)
    r = D.read_npy(p, rate_Hz=RATE)
    assert r.height_m == 0.4 and r.source == "h040_a.npy"
    np.testing.assert_array_equal(r.force_N, x)
    assert D.read_npy(x[:, None], rate_Hz=RATE).n_samples == x.size
    with pytest.raises(DataError, match="1-D"):
        D.read_npy(np.zeros((3, 200)), rate_Hz=RATE)
    with pytest.raises(DataError, match="h040_a.npy: a .npy file has no time base"):
        D.load(p)
    assert D.load(p, rate_Hz=RATE)[0].height_m == 0.4


def test_recording_is_frozen():
    r = D.read_npy(raw_force(), rate_Hz=RATE)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.rate_Hz = 1.0
    with pytest.raises(ValueError):
        r.force_N[0] = 1.0


# --------------------------------------------------------------------------------------
# heights, manifest, rates
# --------------------------------------------------------------------------------------


def test_height_sources_and_unknown_height(tmp_path):
    x = raw_force()
    write_csv(tmp_path / "h080_d1.csv", x)
    write_csv(tmp_path / "drop7.csv", x)
    with pytest.raises(
        DataError, match=r"cannot know the drop height of drop7\.csv: pass height_m="
    ):
        D.load(tmp_path)
    (tmp_path / "heights.csv").write_text("file,height_m\ndrop7.csv,0.55\n")
    recs = D.load(
        [tmp_path / "h080_d1.csv", tmp_path / "drop7.csv"], manifest=tmp_path / "heights.csv"
    )
    assert [r.height_m for r in recs] == [0.8, 0.55]
    assert [r.height_m for r in D.load([tmp_path / "drop7.csv"], height_m=1.2)] == [1.2]
    (tmp_path / "heights.csv").unlink()
    (tmp_path / "manifest.csv").write_text("file,height_m\nh080_d1.csv,0.81\ndrop7.csv,0.55\n")
    recs = D.load(tmp_path)  # the manifest in the folder is used, not read as a recording
    assert {r.source: r.height_m for r in recs} == {"h080_d1.csv": 0.81, "drop7.csv": 0.55}
    assert D.height_from_name("raw_h100_two_impacts.wav") == 1.0
    assert D.height_from_name("h1000.csv") is None and D.height_from_name("ch100.csv") is None


def test_a_missing_file_or_manifest_is_a_data_error_naming_the_path(tmp_path):
    readers = {
        "h100.csv": D.read_csv,
        "h100.npy": lambda p: D.read_npy(p, rate_Hz=44100.0),
        "h100.wav": D.read_wav,
        "h100.mat": D.read_mat,
        "h100.uff": D.read_uff,
        "h100.tdms": D.read_tdms,
    }
    for name, read in readers.items():
        missing = tmp_path / "gone" / name
        with pytest.raises(DataError, match=f"^{re.escape(str(missing))}: no such file"):
            read(missing)
        with pytest.raises(DataError, match="no such file"):
            D.read_file(str(missing), rate_Hz=44100.0)
    (tmp_path / "h100.csv").mkdir()
    with pytest.raises(DataError, match=r"h100\.csv: a directory, not a file"):
        D.read_csv(tmp_path / "h100.csv")
    write_csv(tmp_path / "h080_d1.csv", raw_force())
    manifest = tmp_path / "heights.csv"
    with pytest.raises(DataError, match=f"^manifest {re.escape(str(manifest))}: no such file"):
        D.load(tmp_path / "h080_d1.csv", manifest=manifest)


def test_different_rates_rejected(tmp_path):
    x = raw_force()
    write_csv(tmp_path / "h100_a.csv", x)
    write_csv(tmp_path / "h100_b.csv", x, rate=48000)
    with pytest.raises(DataError, match=r"h100_a\.csv: 44100 Hz, h100_b\.csv: 48000 Hz"):
        D.load(tmp_path)
    a, b = (D.condition(D.read_csv(p)) for p in sorted(tmp_path.glob("*.csv")))
    with pytest.raises(DataError, match=r"different sample rates.*h100_b\.csv: 48000 Hz"):
        D.average([a, b])


# --------------------------------------------------------------------------------------
# bad data
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "content,match",
    [
        ("", "empty file"),
        ("time_s,force_N\n", "no data rows"),
        ("# only a comment\n\n", "empty file"),
        ("a,b\n1,2\n", "no force column"),
        ("time_s,force_lbf\n0,1\n", "unknown unit 'lbf'"),
        (
            "time_s,force_N\n" + "".join(f"{i / RATE:.7f},1.0\n" for i in range(50)),
            "only 50 samples",
        ),
    ],
)
def test_bad_csv_structure(tmp_path, content, match):
    p = tmp_path / "bad_h100.csv"
    p.write_text(content)
    with pytest.raises(DataError, match=match) as e:
        D.read_csv(p)
    assert "bad_h100.csv" in str(e.value)


def test_bad_csv_values(tmp_path):
    x = raw_force()
    good = write_csv(tmp_path / "g.csv", x).read_text().splitlines()

    def variant(name, k, new):
        lines = list(good)
        lines[k] = new
        p = tmp_path / name
        p.write_text("\n".join(lines) + "\n")
        return p

    with pytest.raises(DataError, match=r"trunc\.csv: line 4001 has 1 of 2 fields.*truncated"):
        D.read_csv(variant("trunc.csv", 4000, good[4000].split(",")[0] + ","))
    p = tmp_path / "cut.csv"
    p.write_text("\n".join(good[:3000]) + "\n0.0679")  # writer stopped mid-line
    with pytest.raises(DataError, match="cut.csv: line 3001 .*truncated"):
        D.read_csv(p)
    with pytest.raises(DataError, match=r"text\.csv: line 11: non-numeric value 'abc'"):
        D.read_csv(variant("text.csv", 10, "0.0002268,abc"))
    with pytest.raises(DataError, match=r"nan\.csv: 1 sample\(s\) are NaN or inf"):
        D.read_csv(variant("nan.csv", 10, "0.0002268,nan"))
    with pytest.raises(DataError, match=r"inf\.csv: 1 sample\(s\) are NaN or inf"):
        D.read_csv(variant("inf.csv", 10, "0.0002268,inf"))
    with pytest.raises(DataError, match=r"gap\.csv: non-uniform time column"):
        p = tmp_path / "gap.csv"
        p.write_text("\n".join(good[:2000] + good[2001:]) + "\n")  # one sample missing
        D.read_csv(p)
    with pytest.raises(DataError, match=r"back\.csv: time column is not strictly increasing"):
        D.read_csv(variant("back.csv", 10, "0.0000000,1.0"))


def test_clipping_flat_top(tmp_path):
    x = raw_force()
    top = np.argmax(x)
    x[top - 1 : top + 3] = x[top]
    for name, make in [
        ("clip.csv", lambda p: write_csv(p, x)),
        ("clip.wav", lambda p: p.write_bytes(wav_bytes(x.astype("<f4").tobytes(), tag=3, bits=32))),
        ("clip.npy", lambda p: np.save(p, x)),
    ]:
        p = tmp_path / name
        make(p)
        with pytest.raises(DataError, match=rf"{name}: clipped: 4 consecutive samples"):
            D.load(p, height_m=1.0, rate_Hz=RATE if name.endswith("npy") else None)
    # integer WAV: any sample at full scale
    codes = np.clip(np.round(raw_force(peak_N=1500.0) / 1000.0 * 32768), -32768, 32767).astype(
        "<i2"
    )
    p = tmp_path / "clip_int.wav"
    p.write_bytes(wav_bytes(codes.tobytes(), tag=1, bits=16))
    with pytest.raises(DataError, match=r"clip_int\.wav: clipped: \d+ sample\(s\) at full scale"):
        D.read_wav(p, calibration_N_per_FS=1000.0)
    # 24 bit: one sample at the largest or the smallest code is clipping, one step below is not
    codes = np.round(raw_force() / 2000.0 * 2**23).astype(np.int64)
    for code, clipped in ((2**23 - 1, True), (2**23 - 2, False), (-(2**23), True)):
        c = codes.copy()
        c[1000] = code
        b = (c & 0xFFFFFF).astype("<u4").tobytes()
        p = tmp_path / "clip24.wav"
        with wave.open(str(p), "wb") as w:
            w.setnchannels(1)
            w.setsampwidth(3)
            w.setframerate(RATE)
            w.writeframes(b"".join(b[i : i + 3] for i in range(0, len(b), 4)))
        if clipped:
            with pytest.raises(
                DataError,
                match=r"clip24\.wav: clipped: 1 sample\(s\) at full scale \(first at sample 1000\)",
            ):
                D.read_wav(p, calibration_N_per_FS=2000.0)
        else:
            assert D.read_wav(p, calibration_N_per_FS=2000.0).force_N[1000] == pytest.approx(
                2000.0 * code / 2**23
            )


def test_bad_wav_files(tmp_path):
    x = raw_force().astype("<f4")
    full = wav_bytes(x.tobytes(), tag=3, bits=32)
    cases = {
        "empty.wav": (b"", "empty file"),
        "trunc.wav": (full[: len(full) // 2], "truncated file: the header declares"),
        "notwav.wav": (b"hello world, not a wav file at all", "not a RIFF/WAVE"),
        "short.wav": (wav_bytes(x[:40].tobytes(), tag=3, bits=32), "only 40 samples"),
        "alaw.wav": (wav_bytes(x.tobytes(), tag=6, bits=32), "WAV format ALAW is not supported"),
    }
    for name, (blob, match) in cases.items():
        p = tmp_path / name
        p.write_bytes(blob)
        with pytest.raises(DataError, match=rf"{name}: {match}"):
            D.read_wav(p)
    # truncated integer WAV written by the stdlib (frames missing at the end)
    p = tmp_path / "trunc_int.wav"
    with wave.open(str(p), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(np.zeros(3000, "<i2").tobytes())
    p.write_bytes(p.read_bytes()[:-2000])
    with pytest.raises(DataError, match=r"trunc_int\.wav: truncated"):
        D.read_wav(p, calibration_N_per_FS=1.0)


def test_no_impact_and_impact_off_the_end(tmp_path):
    noise = D.read_npy(
        NOISE_N * np.random.default_rng(3).standard_normal(4410), rate_Hz=RATE, source="quiet.npy"
    )
    with pytest.raises(DataError, match=r"quiet\.npy: no impact found.*below the threshold 10 N"):
        D.condition(noise)
    late = D.read_npy(raw_force(onset=4100), rate_Hz=RATE, source="late.npy")
    with pytest.raises(DataError, match=r"late\.npy: the impact .* runs off the end"):
        D.condition(late)
    tight = D.read_npy(raw_force(onset=3000), rate_Hz=RATE, source="tight.npy")
    with pytest.raises(DataError, match=r"tight\.npy: the window of 50 ms would run past the end"):
        D.condition(tight)
    assert D.condition(tight, window_s=0.025).n_samples == round(0.025 * RATE)
    with pytest.raises(DataError, match=r"tight\.npy: window_s=10 ms cuts the impact"):
        D.condition(tight, window_s=0.01)
    early = D.read_npy(raw_force(onset=30), rate_Hz=RATE, source="early.npy")
    with pytest.raises(DataError, match=r"early\.npy: only \d+ pre-trigger samples"):
        D.condition(early)


# --------------------------------------------------------------------------------------
# onsets
# --------------------------------------------------------------------------------------


def test_onset_subsample_precision_noise_free():
    """Absolute onset error against the analytic 5 % crossing: < 0.05 sample (here ~1e-3)."""
    T = 0.002
    u5 = 0.1  # solve u^3 exp(3(1-u)) = 0.05 for the analytic crossing
    for _ in range(60):
        g = u5**3 * np.exp(3 * (1 - u5)) - 0.05
        u5 -= g / (u5**2 * np.exp(3 * (1 - u5)) * (3 - 3 * u5))
    t = np.arange(2000) / RATE
    errors = []
    for shift in np.linspace(0, 1, 11):
        t0 = (500 + shift) / RATE
        x = smooth_pulse_N(t, t0, 500.0, T)
        onset = D.locate_onset(x, RATE, fraction=0.05)
        errors.append((onset - (t0 + u5 * T)) * RATE)
    assert np.max(np.abs(errors)) < 0.05


def test_onset_follows_fractional_shift_of_a_filtered_pulse():
    """Half-sine through the 1250 Hz chain, sampled with offsets of k/32 sample."""
    over = 32
    tf = np.arange(3000 * over) / (RATE * over)
    fine = lowpass_np(pulse_N(tf, 600 / RATE, 500.0), 1250.0, RATE * over)
    true0 = None
    for k in range(0, over, 3):
        # x[i] = s((i + 1 - k/over) / rate): the pulse sits k/over sample later in x
        x = fine[over - k :: over]
        onset = D.locate_onset(x, RATE) * RATE
        true0 = onset if true0 is None else true0
        assert abs((onset - true0) - k / over) < 0.05


def test_onset_precision_with_noise_bound():
    """With 0.8 N white noise the onset scatters by about sigma / slope (stated bound: 1.5x)."""
    T = 0.002
    t = np.arange(2000) / RATE
    clean = smooth_pulse_N(t, 500.3 / RATE, 500.0, T)
    ref = D.locate_onset(clean, RATE)
    j = int(ref * RATE)
    slope_per_sample = clean[j + 1] - clean[j]
    predicted = NOISE_N / slope_per_sample  # samples
    rng = np.random.default_rng(4)
    err = np.array(
        [
            (D.locate_onset(clean + NOISE_N * rng.standard_normal(t.size), RATE) - ref) * RATE
            for _ in range(200)
        ]
    )
    rms = np.sqrt(np.mean(err**2))
    assert rms < 1.5 * predicted
    assert abs(np.mean(err)) < 0.05 + 3 * predicted / np.sqrt(err.size)


def test_condition_aligns_fractional_pretriggers():
    t = np.arange(4410) / RATE
    outs = []
    for pre in (600.0, 733.25, 811.5, 900.875):
        x = lowpass_np(pulse_N(t, pre / RATE, 700.0), 1250.0, RATE) + 0.3  # offset -> baseline
        outs.append(D.condition(D.read_npy(x, rate_Hz=RATE, source=f"p{pre}")))
    for c in outs[1:]:
        assert c.onset_s == outs[0].onset_s == 0.002
        np.testing.assert_allclose(c.force_N, outs[0].force_N, atol=1e-3 * 700)
    nal = D.condition(D.read_npy(x, rate_Hz=RATE), align=False)
    assert 0.002 <= nal.onset_s < 0.002 + 1 / RATE
    # an extra causal low-pass delays the onset by about the filter's group delay (0.33 ms)
    lp = D.condition(D.read_npy(x, rate_Hz=RATE), lowpass_Hz=1250.0, align=False)
    raw_onset = float(outs[-1].notes[-1].split("onset at ")[1].split(" s")[0])
    lp_onset = float(lp.notes[-1].split("onset at ")[1].split(" s")[0])
    assert 0.25e-3 < lp_onset - raw_onset < 0.4e-3 and lp.lowpass_Hz == 1250.0


# --------------------------------------------------------------------------------------
# averaging
# --------------------------------------------------------------------------------------


def _shifted_copies(n=2205, onset0=88.2, shifts=(0.0, 0.3, -2.7, 5.5, 11.125)):
    """Smooth pulse (band-limited enough for Fourier shifts) in records with known onsets."""
    t = np.arange(n) / RATE
    recs = []
    for k, d in enumerate(shifts):
        onset = (onset0 + d) / RATE
        x = smooth_pulse_N(t, onset, 800.0, 0.003) * np.exp(-np.clip(t - onset, 0, None) / 0.004)
        recs.append(
            D.Recording(
                source=f"h100_s{k}",
                height_m=1.0 + 0.001 * k,
                rate_Hz=RATE,
                force_N=x,
                onset_s=onset,
            )
        )
    return recs


def test_average_frequency_and_time_reproduce_the_pulse():
    recs = _shifted_copies()
    target = recs[0].force_N
    fa = D.average(recs, domain="frequency")
    assert fa.onset_s == recs[0].onset_s and fa.height_m == pytest.approx(1.002)
    np.testing.assert_allclose(fa.force_N, target, atol=2e-3 * target.max())
    ta = D.average(recs, domain="time")
    np.testing.assert_allclose(ta.force_N, fa.force_N, atol=1e-9 * target.max())
    for interpolation in ("linear", "cubic"):
        tl = D.average(recs, domain="time", interpolation=interpolation)
        np.testing.assert_allclose(tl.force_N, target, atol=1e-2 * target.max())
    # without alignment the average would be smeared
    unaligned = np.mean([r.force_N for r in recs], axis=0)
    assert np.abs(unaligned - target).max() > 0.02 * target.max()


def test_average_of_conditioned_drops_reduces_noise():
    h100 = [D.condition(r) for r in D.load_examples("h100_d*.csv")]
    avg = D.average(h100)
    assert avg.height_m == pytest.approx(1.0) and avg.n_samples == h100[0].n_samples
    tail = slice(int(0.03 * RATE), None)  # after the contact: noise only
    single = np.mean([np.std(c.force_N[tail]) for c in h100])
    assert np.std(avg.force_N[tail]) < 0.6 * single  # ~1/sqrt(5) = 0.45
    assert abs(avg.peak_N - np.mean([c.peak_N for c in h100])) < 5.0


def test_average_warns_on_heights_and_needs_onsets():
    recs = _shifted_copies()
    recs[1] = recs[1].replace(height_m=1.5)
    with pytest.warns(DataWarning, match="heights differ by more than 2 cm"):
        D.average(recs)
    with pytest.raises(DataError, match="h100_s0: no onset_s"):
        D.average([recs[0].replace(onset_s=None)])


def test_fractional_shift_names_an_unknown_interpolation_even_for_no_shift():
    from rbjax.data import fractional_shift

    with pytest.raises(ValueError, match="interpolation='sinc'"):
        fractional_shift(np.ones(8), 0.0, interpolation="sinc")
    with pytest.raises(ValueError, match="interpolation='sinc'"):
        fractional_shift(np.ones(8), 0.5, interpolation="sinc")
