"""Faults of real force records (rbjax.data.clean, condition, load): each one built from a clean
simulated 1 s record (tests/synthetic_records.py) with a known, injected fault, and the
outcome checked against what was injected: the fault is mended and logged (the conditioned
window then matches the clean one's to a small fraction of the noise), or refused by name.
The fit on a set of such records is tests/fit/test_fit_faults.py."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

import rbjax.data as D
from rbjax import JIS_RUBBER_BALL, KelvinVoigt
from rbjax.data import examples_dir

from scipy_reference import reference_impact
from synthetic_records import (
    CONTACT_START_S,
    CUTOFF_HZ,
    FAULT_BALL_E_PA,
    FAULT_DAMPING_NS_PER_M,
    FAULT_START_S,
    HEIGHTS_M,
    NOISE_N,
    RATE_HZ,
    SOS,
    long_records,
    sampled_force,
    with_faults,
    write_int_wav,
)

H = 4  # the 1.0 m drop
WINDOW = {"window_s": 0.03, "pre_onset_s": 0.003}


@pytest.fixture(scope="module")
def drop():
    t, forces = long_records()
    rec = D.Recording(
        source="h100.csv",
        height_m=HEIGHTS_M[H],
        rate_Hz=RATE_HZ,
        force_N=forces[H],
        lowpass_Hz=CUTOFF_HZ,
    )
    return t, rec, D.condition(D.clean(rec), **WINDOW)


def conditioned(rec, force):
    return D.condition(D.clean(rec.replace(force_N=force)), **WINDOW)


def test_a_clean_record_is_left_as_it_is(drop):
    _, rec, clean = drop
    out = D.clean(rec)
    np.testing.assert_array_equal(out.force_N, rec.force_N)
    log = clean.conditioning
    assert log["polarity"] == "as recorded" and log["drift_N_per_s"] is None and log["hum"] is None
    assert log["further_impacts"] == [] and abs(log["offset_N"]) < 0.05
    # docs/guides/loader.md: every shipped record comes back bitwise unchanged, the
    # 30 emulated recordings (noise and all) and the raw WAV whose rebound ``condition`` cuts
    shipped = [
        *D.load_examples(),
        *D.load([examples_dir() / "raw_h100_two_impacts.wav"], height_m=1.0),
    ]
    assert len(shipped) == 31
    for r in shipped:
        np.testing.assert_array_equal(D.clean(r).force_N, r.force_N)


def test_clean_simulated_records_of_three_lengths_come_back_bitwise_unchanged():
    """docs/guides/loader.md, mains hum: no false repair on 3 × 288 simulated clean
    records of 0.06, 0.1 and 0.3 s. The records: the six drops of the fault tests (the scipy
    solution of Eq. 7, tests/synthetic_records.py) at 48 noise seeds each (0.8 N white noise
    through the 1250 Hz chain), contact 10 ms (+ a fraction of a sample) into the record."""
    ball = JIS_RUBBER_BALL.replace(youngs_Pa=FAULT_BALL_E_PA)
    damping = KelvinVoigt(FAULT_DAMPING_NS_PER_M)
    refs = [
        reference_impact(h, ball, damping=damping, blocked_force="momentum", rtol=1e-11)
        for h in HEIGHTS_M
    ]
    checked = 0
    for record_s in (0.06, 0.1, 0.3):
        t = np.arange(int(round(record_s * RATE_HZ))) / RATE_HZ
        for seed in range(48):
            rng = np.random.default_rng(seed)
            for h, ref in zip(HEIGHTS_M, refs, strict=True):
                start = CONTACT_START_S + rng.uniform(0, 1 / RATE_HZ)
                noisy = sampled_force(ref, t - start) + rng.normal(0.0, NOISE_N, t.size)
                rec = D.Recording(
                    source=f"h{round(100 * h):03d}_s{seed}.csv",
                    height_m=h,
                    rate_Hz=RATE_HZ,
                    force_N=scipy.signal.sosfilt(SOS, noisy),
                    lowpass_Hz=CUTOFF_HZ,
                )
                out = D.clean(rec)
                np.testing.assert_array_equal(out.force_N, rec.force_N, err_msg=rec.source)
                checked += 1
    assert checked == 3 * 288


def test_offset_and_drift_are_removed_and_logged(drop):
    t, rec, clean = drop
    out = conditioned(rec, with_faults(t, rec.force_N, offset_N=25.0, drift_N_per_s=12.0))
    log = out.conditioning
    assert log["drift_N_per_s"] == pytest.approx(12.0, rel=0.01)
    # the drift is removed as a line through zero at the impact: the offset there remains
    assert log["offset_N"] == pytest.approx(
        25.0 + 12.0 * FAULT_START_S + clean.conditioning["offset_N"], abs=0.05
    )
    assert np.abs(out.force_N - clean.force_N).max() < 0.01  # noise rms ~0.19 N


@pytest.mark.parametrize("mains_Hz, amplitude_N", [(50.02, 3.0), (59.97, 4.0)])
def test_mains_hum_is_removed_and_logged(drop, mains_Hz, amplitude_N):
    t, rec, clean = drop
    out = conditioned(rec, with_faults(t, rec.force_N, hum=(mains_Hz, amplitude_N)))
    hum = out.conditioning["hum"]
    assert hum["frequency_Hz"] == pytest.approx(mains_Hz, abs=0.005)
    assert hum["amplitude_N"] == pytest.approx(amplitude_N, rel=0.02)
    assert out.conditioning["drift_N_per_s"] is None
    resid = out.force_N - clean.force_N
    assert np.sqrt(np.mean(resid**2)) < 0.03 and np.abs(resid).max() < 0.08  # of a 3-4 N hum


def test_inverted_sign_is_flipped_with_a_warning(drop):
    t, rec, clean = drop
    with pytest.warns(D.DataWarning, match="inverted sign; flipped"):
        out = conditioned(rec, with_faults(t, rec.force_N, inverted=True))
    assert out.conditioning["polarity"] == "inverted: sign flipped"
    np.testing.assert_array_equal(out.force_N, clean.force_N)


def test_the_rebound_is_cut_and_reported(drop):
    t, rec, clean = drop
    with pytest.warns(D.DataWarning, match="1 further impact"):
        out = conditioned(rec, with_faults(t, rec.force_N, rebound_after_s=0.7))
    (rebound,) = out.conditioning["further_impacts"]
    first = clean.conditioning["impact_s"]
    assert out.conditioning["impact_s"] == first
    assert rebound["time_s"] == pytest.approx(first + 0.7, abs=2e-3)
    assert rebound["peak_N"] == pytest.approx(0.5 * rec.force_N.max(), rel=0.02)
    np.testing.assert_allclose(out.force_N, clean.force_N, atol=1e-9)
    assert "0.8" in D.describe_conditioning(out.conditioning) and "cut" in D.describe_conditioning(
        out.conditioning
    )


def test_every_fault_at_once(drop):
    t, rec, clean = drop
    faulty = with_faults(
        t,
        rec.force_N,
        offset_N=-40.0,
        drift_N_per_s=-8.0,
        hum=(50.0, 2.5),
        inverted=True,
        rebound_after_s=0.7,
    )
    with pytest.warns(D.DataWarning):
        out = conditioned(rec, faulty)
    log = out.conditioning
    assert log["polarity"] != "as recorded" and log["hum"] and len(log["further_impacts"]) == 1
    assert log["drift_N_per_s"] == pytest.approx(-8.0, rel=0.02)
    assert np.sqrt(np.mean((out.force_N - clean.force_N) ** 2)) < 0.03


def test_cut_off_and_no_impact_records_are_named_errors(drop):
    t, rec, _ = drop
    cut = rec.replace(force_N=rec.force_N[: int((FAULT_START_S + 0.008) * RATE_HZ)])  # mid-contact
    with pytest.raises(
        D.RecordCutOffError, match=r"h100\.csv: the impact at 0\.1\d+ s runs off the end"
    ):
        D.condition(D.clean(cut), **WINDOW)
    late = rec.replace(
        force_N=rec.force_N[: int((FAULT_START_S + 0.025) * RATE_HZ)]
    )  # contact over, window not
    with pytest.raises(D.RecordCutOffError, match="would run past the end of the record"):
        D.condition(D.clean(late), **WINDOW)
    quiet = rec.replace(force_N=rec.force_N[: int(0.09 * RATE_HZ)])  # the pre-trigger only
    with pytest.raises(D.NoImpactError, match=r"h100\.csv: no impact found"):
        D.condition(D.clean(quiet), **WINDOW)
    assert issubclass(D.RecordCutOffError, D.DataError) and issubclass(D.NoImpactError, D.DataError)


@pytest.mark.parametrize("bits", [16, 24, 32])
def test_integer_wav_with_a_calibration(tmp_path, drop, bits):
    _, rec, _ = drop
    p = tmp_path / f"h100_{bits}bit.wav"
    write_int_wav(p, rec.force_N, bits, 5000.0)
    back = D.load(p, calibration_N_per_FS=5000.0)[0]
    assert back.rate_Hz == RATE_HZ and back.height_m == 1.0
    step = 5000.0 / 2 ** (bits - 1)
    np.testing.assert_allclose(back.force_N, rec.force_N, rtol=0, atol=0.5 * step * (1 + 1e-9))
    with pytest.raises(D.DataError, match="integer PCM WAV: pass calibration_N_per_FS="):
        D.load(p)


def test_a_clipped_record_among_good_ones(tmp_path, drop):
    _, rec, _ = drop
    write_int_wav(tmp_path / "h100_a.wav", rec.force_N, 16, 5000.0)
    write_int_wav(
        tmp_path / "h100_b.wav", rec.force_N, 16, 1000.0
    )  # the peak (1.6 kN) is off the scale
    (tmp_path / "manifest.csv").write_text(
        "file,height_m,calibration_N_per_FS\nh100_a.wav,1.0,5000\nh100_b.wav,1.0,1000\n"
    )
    with pytest.raises(
        D.ClippedRecordError, match=r"h100_b\.wav: clipped: \d+ sample\(s\) at full scale"
    ):
        D.load(tmp_path)
    good, left_out = D.load(tmp_path, strict=False)
    assert isinstance(good, D.Recording) and good.source == "h100_a.wav"
    assert (
        isinstance(left_out, D.Excluded)
        and left_out.source == "h100_b.wav"
        and "clipped" in left_out.reason
    )
