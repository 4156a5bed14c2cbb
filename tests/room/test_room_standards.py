"""ISO 717-2:2020 Annex D rating and ISO 16283-2 normalisation against printed values and
closed forms; the Fast detector of a sampled exponential decay against g(C)."""

import math

import numpy as np
import pytest

from rbjax.room import standards as st
from rbjax.room.detector import time_weighting


def test_iso_717_2_table_d4_example_rates_55_dB():
    # ISO 717-2:2020 Annex D, Table D.4: octave levels 63-500 Hz
    assert st.rating_dB([65.3, 64.5, 58.0, 55.8]) == 55
    # the unrounded sum by hand: 10 lg(10^3.91 + 10^4.84 + 10^4.94 + 10^5.26)
    by_hand = 10 * math.log10(10**3.91 + 10**4.84 + 10**4.94 + 10**5.26)
    assert float(st.a_weighted_sum_dB([65.3, 64.5, 58.0, 55.8])) == pytest.approx(
        by_hand, abs=1e-12
    )


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (54.49, 54),
        (54.5, 55),
        (54.51, 55),
        (54.5 - 1e-10, 55),
        (54.4999, 54),
        (-0.5, -1),
        (-0.4, 0),
    ],
)
def test_rounding_branches(value, expected):
    assert st.round_rating(value) == expected


def test_rating_of_levels_summing_to_exactly_half():
    # one band only audible: L + A = 50.5 exactly in decimal, the others far below
    levels = [0.0, 0.0, 0.0, 50.5 + 3.2]
    assert st.round_rating(st.a_weighted_sum_dB(levels)) == 51


def test_a_weights_match_the_iec_61672_formula():
    # IEC 61672-1:2013 Eq. E.6 with the constants of Annex E; table values to 0.1 dB
    f1, f2, f3, f4 = 20.598997, 107.65265, 737.86223, 12194.217
    a1000 = -2.000

    def a_weight(f):
        return (
            20
            * math.log10(
                f4**2
                * f**4
                / ((f**2 + f1**2) * math.sqrt((f**2 + f2**2) * (f**2 + f3**2)) * (f**2 + f4**2))
            )
            - a1000
        )

    for fraction in (1, 3):
        table = st.A_WEIGHTS_OCTAVE_dB if fraction == 1 else st.A_WEIGHTS_THIRD_OCTAVE_dB
        for label, value in table.items():
            # the table is computed at the exact base-ten mid-band frequency
            x = round(10 * math.log10(float(label) / 1000))
            f = 1000 * 10 ** (x / 10)
            # the printed table to its 0.1 dB (IEC 61672-1 rounds -13.35 at 158.5 Hz to -13.4)
            assert value == pytest.approx(a_weight(f), abs=0.051), label


def test_fast_correction_closed_form_values():
    assert float(st.fast_correction_dB(1.0)) == pytest.approx(1.94, abs=0.01)
    assert float(st.fast_correction_dB(2.0)) == pytest.approx(3.55, abs=0.01)  # 3.545
    assert float(st.fast_correction_dB(0.5)) == 0.0
    # continuity through C = 1 (T = 6 ln10 τ)
    t1 = 6 * math.log(10) * 0.125
    assert float(st.fast_max_of_decay(t1)) == pytest.approx(math.exp(-1), rel=1e-12)
    assert float(st.fast_max_of_decay(t1 * (1 + 1e-5))) == pytest.approx(
        float(st.fast_max_of_decay(t1 * (1 + 2e-6))), rel=1e-5
    )


@pytest.mark.parametrize("reverberation_s", [0.5, 1.0, 2.0])
def test_sampled_fast_detector_on_an_exponential_decay_gives_g(reverberation_s):
    rate = 48000.0
    t = np.arange(int(rate * 3 * reverberation_s)) / rate
    p2 = np.exp(-6 * math.log(10) / reverberation_s * t)
    y = np.asarray(time_weighting(p2, rate))
    assert 10 * math.log10(y.max()) == pytest.approx(
        10 * math.log10(float(st.fast_max_of_decay(reverberation_s))), abs=0.01
    )


def test_normalisation():
    # V = 100 m³, T = 1 s: +3.01 dB for the volume, −1.94 dB for the slower decay
    out = float(st.normalised_level_dB(60.0, 100.0, 1.0))
    assert out == pytest.approx(60.0 + 10 * math.log10(2.0) - 1.94, abs=0.005)


@pytest.mark.parametrize(
    ("args", "match"), [((60.0, 0.0, 0.5), "volume_m3"), ((60.0, 50.0, -1.0), "reverberation_s")]
)
def test_normalisation_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        st.normalised_level_dB(*args)


def test_rating_bad_input():
    with pytest.raises(ValueError, match="valid: 4"):
        st.rating_dB([60.0, 60.0, 60.0])
    with pytest.raises(ValueError, match="non-finite"):
        st.rating_dB([60.0, np.nan, 60.0, 60.0])
    assert st.rating_dB([60.0] * 12, fraction=3) == st.round_rating(
        10 * math.log10(sum(10 ** ((60 + a) / 10) for a in st.A_WEIGHTS_THIRD_OCTAVE_dB.values()))
    )
