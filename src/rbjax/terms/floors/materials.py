"""Material presets for floor plates: Young's modulus, density and Poisson's ratio, with sources.

A thin plate's drive-point impedance Z = 8√(B′m″)
(``rbjax.terms.floors.kinds.plate_impedance_Ns_per_m``) needs E, ρ and ν; the values below are
the standard design values of the codes named in each ``source``. They are the values of a
material grade, not of a given product: take a product's declared values where it has them
(``rbjax.terms.floors.presets.load_floor`` reads them from a file).

- ``concrete``: normal-weight reinforced concrete, strength class C30/37. E_cm = 33 GPa
  (EN 1992-1-1:2004, Table 3.1), ν = 0.2 (EN 1992-1-1, §3.1.3(4), uncracked concrete),
  ρ = 2300 kg/m³ (EN ISO 10456:2007, Table 3, reinforced concrete with 1 % steel; EN 12524).
  Hopkins, *Sound Insulation* (2007), uses dense concrete of this kind (ρ ≈ 2200–2400 kg/m³,
  E ≈ 30–40 GPa) for the heavy floors of building acoustics.
- ``steel``: structural steel, E = 210 GPa, ν = 0.3 (EN 1993-1-1:2005, §3.2.6),
  ρ = 7850 kg/m³ (EN 1991-1-1:2002, Table A.4); Cremer, Heckl & Petersson, *Structure-Borne
  Sound*, 3rd ed. (2005), Table 3.1 gives the same order (E ≈ 200 GPa, ρ ≈ 7800 kg/m³).
- ``osb``: oriented strand board OSB/3 (load-bearing, humid conditions). EN 300:2006, Table 3,
  requires a modulus of elasticity in bending of at least 3500 N/mm² along the major axis and
  1400 N/mm² along the minor axis; the isotropic equivalent is their geometric mean
  √(3500·1400) N/mm² = 2.21 GPa (the point impedance of an orthotropic plate is
  8√(m″√(B′_x B′_y)): the plate acts as an isotropic one of modulus √(E_x E_y)). These are
  minimum requirements: a real board is stiffer (EN 12369-1 mean values are ~40 % higher),
  which raises Z by ~20 %. ρ = 650 kg/m³ (EN ISO 10456:2007, Table 3, OSB; EN 12524).
- ``chipboard``: resin-bonded particleboard for load-bearing floors (EN 312 types P4/P5,
  20–25 mm). E = 2.5 GPa: the order of the minimum bending modulus EN 312:2010 requires of
  these types and thicknesses (about 2.3–2.6 GPa by type; ρ-independent requirement);
  isotropic in the plane (flat-pressed). ρ = 650 kg/m³ (EN ISO 10456:2007, Table 3, lists
  particleboard at 300, 600 and 900 kg/m³; flooring grades of 18–25 mm are declared at
  ~620–680 kg/m³).
- ``timber-c24``: solid softwood of strength class C24 along the grain: E_0,mean = 11 GPa,
  ρ_mean = 420 kg/m³ (EN 338:2016, Table 1). Timber is strongly orthotropic
  (E_90,mean = 0.37 GPa): as an isotropic plate this is the stiff direction only.
- ``clt``: cross-laminated timber (EN 16351:2015) of five equal C24 layers. The bending
  stiffness per width of the layup is B′_x = (E_0 I_∥ + E_90 I_⊥), B′_y = (E_0 I_⊥ + E_90 I_∥),
  with I_∥ and I_⊥ the second moments of the layers along and across
  (``cross_laminated_youngs_Pa``); the isotropic equivalent √(E_x E_y) = 4.76 GPa for five equal
  layers, any thickness (E_0 = 11 GPa, E_90 = 0.37 GPa from EN 338). ρ = 470 kg/m³: C24 lamellas
  (ρ_mean 420) with glue lines; CLT manufacturers' European Technical Assessments declare
  450–500 kg/m³.

Poisson's ratio of the wood-based panels is taken as 0.3 (no code value; it enters Z as
1/√(1 − ν²), so ±0.1 changes Z by < 3 %).

Each material also names the plate thicknesses a floor of it plausibly has
(``Material.thickness_range_m``, generous on purpose): concrete 40–1200 mm (a screed-like
topping to the thickest transfer slabs), steel 1–100 mm, OSB 6–40 mm and particleboard 10–50 mm
(the thickness classes of EN 300 and EN 312), solid timber 15–300 mm, CLT 50–500 mm (three to
eleven lamellas of EN 16351). A thickness outside is refused where a plate is built from a
material name (``Material.check_thickness``): mostly a unit slip (millimetres given as metres).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..._validate import check_range


@dataclasses.dataclass(frozen=True)
class Material:
    """An isotropic elastic plate material.

    Attributes:
        name: the preset name (lower case, ``MATERIALS`` key).
        youngs_Pa: Young's modulus E (Pa, > 0).
        density_kg_per_m3: density ρ (kg/m³, > 0).
        poisson: Poisson's ratio ν in (−1, 0.5].
        source: where the values come from (code, table).
        thickness_range_m: the plausible plate thicknesses (lower, upper), m, of a floor of the
            material (module docstring; default: any positive thickness).

    Raises:
        ValueError: a Young's modulus or density not finite and > 0, a Poisson ratio outside
            (−1, 0.5], or a thickness range that is not 0 ≤ lower < upper.
    """

    name: str
    youngs_Pa: float
    density_kg_per_m3: float
    poisson: float
    source: str
    thickness_range_m: tuple[float, float] = (0.0, math.inf)

    def __post_init__(self):
        check_range("youngs_Pa", self.youngs_Pa, lower=0.0)
        check_range("density_kg_per_m3", self.density_kg_per_m3, lower=0.0)
        check_range("poisson", self.poisson, lower=-1.0, upper=0.5, upper_open=False)
        lower, upper = self.thickness_range_m
        if not 0.0 <= lower < upper:
            raise ValueError(
                f"thickness_range_m={self.thickness_range_m!r} is not a range 0 ≤ lower < upper"
            )

    def check_thickness(self, thickness_m) -> None:
        """Refuse a plate thickness outside ``thickness_range_m``.

        Args:
            thickness_m: the plate's thickness, m (a concrete number or array: every value is
                checked).

        Raises:
            ValueError: a thickness not finite and > 0, or outside the material's plausible
                range (the message names the parameter, the first such value and the range).
        """
        check_range("thickness_m", thickness_m, lower=0.0)
        lower, upper = self.thickness_range_m
        values = np.asarray(thickness_m, dtype=float).reshape(-1)
        outside = values[(values < lower) | (values > upper)]
        if outside.size:
            raise ValueError(
                f"thickness_m={float(outside[0])!r} is outside the plausible range "
                f"[{lower:g}, {upper:g}] m of material {self.name!r} (millimetres given as m?)"
            )


def cross_laminated_youngs_Pa(parallel_Pa: float, perpendicular_Pa: float, layers: int) -> float:
    """The isotropic-equivalent modulus √(E_x E_y) of ``layers`` equal crosswise layers (odd:
    the outer layers run along x), each of modulus ``parallel_Pa`` along its grain and
    ``perpendicular_Pa`` across it (plain lamination theory, shear and gaps neglected)."""
    if layers < 1 or layers % 2 == 0:
        raise ValueError(f"layers={layers!r} is outside the valid range: an odd number ≥ 1")
    check_range("parallel_Pa", parallel_Pa, lower=0.0)
    check_range("perpendicular_Pa", perpendicular_Pa, lower=0.0)
    # second moments of the layers along x and across, per unit width, for a unit layer thickness
    along = across = 0.0
    for k in range(layers):
        z = k - (layers - 1) / 2.0
        moment = 1.0 / 12.0 + z * z
        if k % 2 == 0:
            along += moment
        else:
            across += moment
    total = along + across
    e_x = (parallel_Pa * along + perpendicular_Pa * across) / total
    e_y = (parallel_Pa * across + perpendicular_Pa * along) / total
    return math.sqrt(e_x * e_y)


_C24_PARALLEL_PA = 11.0e9
_C24_PERPENDICULAR_PA = 0.37e9

#: name → ``Material`` (see the module docstring for every value's source).
MATERIALS: dict[str, Material] = {
    m.name: m
    for m in (
        Material(
            "concrete",
            33.0e9,
            2300.0,
            0.2,
            "C30/37: E_cm EN 1992-1-1 Table 3.1, ν EN 1992-1-1 §3.1.3; ρ EN ISO 10456 Table 3 "
            "(reinforced, 1 % steel)",
            (0.04, 1.2),
        ),
        Material(
            "steel",
            210.0e9,
            7850.0,
            0.3,
            "EN 1993-1-1 §3.2.6 (E, ν); EN 1991-1-1 Table A.4 (ρ)",
            (0.001, 0.1),
        ),
        Material(
            "osb",
            math.sqrt(3500.0e6 * 1400.0e6),
            650.0,
            0.3,
            "OSB/3: √(E_major E_minor), EN 300 Table 3 minima; ρ EN ISO 10456 Table 3; ν assumed",
            (0.006, 0.04),
        ),
        Material(
            "chipboard",
            2.5e9,
            650.0,
            0.3,
            "particleboard P4/P5 20–25 mm: E of the EN 312 bending-modulus requirement; ρ EN ISO "
            "10456 / declared; ν assumed",
            (0.01, 0.05),
        ),
        Material(
            "timber-c24",
            _C24_PARALLEL_PA,
            420.0,
            0.3,
            "C24 along the grain: E_0,mean and ρ_mean, EN 338 Table 1; ν assumed",
            (0.015, 0.3),
        ),
        Material(
            "clt",
            cross_laminated_youngs_Pa(_C24_PARALLEL_PA, _C24_PERPENDICULAR_PA, 5),
            470.0,
            0.3,
            "CLT (EN 16351), 5 equal C24 layers: √(E_x E_y) by lamination theory from EN 338 "
            "E_0/E_90; ρ from ETAs; ν assumed",
            (0.05, 0.5),
        ),
    )
}


def material(name: str) -> Material:
    """The ``Material`` preset called ``name`` (``ValueError`` listing the valid names)."""
    try:
        return MATERIALS[name]
    except KeyError:
        raise ValueError(
            f"material={name!r} is not a known material; valid: {', '.join(MATERIALS)}"
        ) from None
