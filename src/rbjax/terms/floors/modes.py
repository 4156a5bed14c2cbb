"""Drive-point modal models (``rbjax.terms.floors.kinds.ModalFloor``) of two idealised floors.

* ``simply_supported_plate_modes``: a rectangular thin (Kirchhoff) plate simply supported on
  its four edges, whose modes are known in closed form.
* ``floating_floor``: a screed on a resilient layer over a base structure, idealised as two
  masses on two springs (the classic mass–spring–mass model of a floating floor;
  ``rbjax.terms.floors.floating.FloatingFloor`` is the same floor with traceable parameters).

Both return a ``ModalFloor`` (masses, frequencies and loss factors seen at the drive point, the
point the ball hits). The values are computed here in NumPy, once: they are static in the
ODE (a new floor compiles a new program).
"""

from __future__ import annotations

import math

import numpy as np

from ..._validate import check_range
from .floating import FloatingFloor
from .kinds import ModalFloor


def _positive(name: str, value) -> float:
    check_range(name, value, lower=0.0)
    return float(value)


def _loss(name: str, value) -> float:
    check_range(name, value, lower=0.0, lower_open=False)
    return float(value)


def simply_supported_plate_modes(
    length_x_m,
    length_y_m,
    thickness_m,
    youngs_Pa,
    density_kg_per_m3,
    poisson,
    loss_factor,
    *,
    drive_x_m,
    drive_y_m,
    max_frequency_Hz,
) -> ModalFloor:
    """The modes up to ``max_frequency_Hz`` of a simply supported rectangular thin plate, as
    seen at the drive point (x, y).

    The plate of sides L_x, L_y, thickness t, bending stiffness B′ = E t³/(12(1 − ν²)) and mass
    per unit area m″ = ρ t has the modes (m, n ≥ 1) of shape φ_mn = sin(mπx/L_x) sin(nπy/L_y) and
    frequency

        f_mn = (π/2) √(B′/m″) ((m/L_x)² + (n/L_y)²)

    (Leissa, *Vibration of Plates*, NASA SP-160, 1969, §4.1, Eq. 4.5; Cremer, Heckl &
    Petersson, *Structure-Borne Sound*, 3rd ed., §5.4). The generalised mass of each mode is
    ∫m″φ² dA = m″L_xL_y/4, so the modal mass seen at the drive point is

        m_mn = (ρ t L_x L_y / 4) / (sin²(mπx/L_x) sin²(nπy/L_y)).

    Modes with a node at the drive point (|φ_mn| < 1e-9: they are not excited there) are left
    out. Every mode gets the same ``loss_factor`` η (viscous at resonance, as in
    ``ModalFloor``). The modes above ``max_frequency_Hz`` are truncated without a residual
    compliance: the truncated model is stiffer than the plate by about
    1/(2π²√(B′m″) f_max) of drive-point compliance (the quasi-static share of the missing
    modes), so choose f_max well above the force's bandwidth.

    Raises ``ValueError`` (naming the argument) for non-positive dimensions, modulus, density or
    maximum frequency, ν outside (−1, 0.5], η < 0, a drive point outside the plate, or no
    mode below ``max_frequency_Hz``.
    """
    lx = _positive("length_x_m", length_x_m)
    ly = _positive("length_y_m", length_y_m)
    t = _positive("thickness_m", thickness_m)
    e = _positive("youngs_Pa", youngs_Pa)
    rho = _positive("density_kg_per_m3", density_kg_per_m3)
    check_range("poisson", poisson, lower=-1.0, upper=0.5, upper_open=False)
    nu = float(poisson)
    eta = _loss("loss_factor", loss_factor)
    f_max = _positive("max_frequency_Hz", max_frequency_Hz)
    check_range("drive_x_m", drive_x_m, lower=0.0, upper=lx)
    check_range("drive_y_m", drive_y_m, lower=0.0, upper=ly)
    x, y = float(drive_x_m), float(drive_y_m)

    bending = e * t**3 / (12.0 * (1.0 - nu**2))
    speed = 0.5 * math.pi * math.sqrt(bending / (rho * t))  # f_mn = speed · ((m/Lx)² + (n/Ly)²)
    m_max = int(math.floor(lx * math.sqrt(f_max / speed)))
    n_max = int(math.floor(ly * math.sqrt(f_max / speed)))
    if m_max < 1 or n_max < 1:
        raise ValueError(
            f"max_frequency_Hz={f_max!r} is below the first mode "
            f"f_11={speed * (lx**-2 + ly**-2):.6g} Hz; valid: a max_frequency_Hz above it"
        )
    m, n = np.meshgrid(np.arange(1, m_max + 1), np.arange(1, n_max + 1), indexing="ij")
    freq = speed * ((m / lx) ** 2 + (n / ly) ** 2)
    shape = np.sin(m * math.pi * x / lx) * np.sin(n * math.pi * y / ly)
    keep = (freq <= f_max) & (np.abs(shape) >= 1e-9)
    if not np.any(keep):
        raise ValueError(
            f"no mode up to max_frequency_Hz={f_max!r} moves at the drive point ({x!r}, {y!r}); "
            "valid: a point off the nodal lines"
        )
    order = np.argsort(freq[keep], kind="stable")
    generalised = rho * t * lx * ly / 4.0
    masses = generalised / shape[keep][order] ** 2
    return ModalFloor(mass_kg=masses, frequency_Hz=freq[keep][order], loss_factor=eta)


def floating_floor(
    screed_thickness_m,
    screed_density_kg_per_m3,
    area_m2,
    dynamic_stiffness_N_per_m3,
    *,
    base_mass_kg,
    base_frequency_Hz,
    layer_loss_factor=0.1,
    base_loss_factor=0.02,
) -> ModalFloor:
    """A floating floor as the two-mode drive-point model of a mass–spring–mass system, with
    static values: ``FloatingFloor(...).modal_floor()`` (the derivation:
    ``rbjax.terms.floors.floating``; use ``FloatingFloor`` itself to differentiate in the
    build-up).

    Raises ``ValueError`` (naming the argument) for a non-positive thickness, density, area,
    dynamic stiffness or base mass, a negative base frequency, or a negative loss factor.
    """
    t = _positive("screed_thickness_m", screed_thickness_m)
    rho = _positive("screed_density_kg_per_m3", screed_density_kg_per_m3)
    area = _positive("area_m2", area_m2)
    s = _positive("dynamic_stiffness_N_per_m3", dynamic_stiffness_N_per_m3)
    m2 = _positive("base_mass_kg", base_mass_kg)
    check_range("base_frequency_Hz", base_frequency_Hz, lower=0.0, lower_open=False)
    f2 = float(base_frequency_Hz)
    eta1 = _loss("layer_loss_factor", layer_loss_factor)
    eta2 = _loss("base_loss_factor", base_loss_factor)

    return FloatingFloor(
        t, rho, area, s, m2, f2, layer_loss_factor=eta1, base_loss_factor=eta2
    ).modal_floor()
