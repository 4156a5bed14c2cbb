"""A floating floor declared by its build-up: a screed on a resilient layer over a base
structure, as the two drive-point modes of a mass–spring–mass system (``FloatingFloor``).

Its parameters are leaves of the pytree (declared, with units and bounds, like every term):
the impact and the room chain (``rbjax.room``) are differentiable in the screed's
mass, the layer's dynamic stiffness and loss and the base, and a new build-up reuses the
compiled programs. ``rbjax.terms.floors.modes.floating_floor`` gives the same floor as a
``ModalFloor`` of static values.

**The modes.** The screed under the ball moves as one rigid mass m₁ = ρ t A (``area_m2``: the
area that moves with the ball, a modelling choice; a real screed bends, so A is the area of
the screed that takes part in the impact), resting on the resilient layer's spring k₁ = s′A
(s′: the layer's dynamic stiffness per unit area, EN 29052-1), over a base structure given as
one mode of mass m₂ and frequency f₂ (its spring to ground k₂ = m₂(2πf₂)²; f₂ = 0: a free
mass). With x₁ (screed) and x₂ (base),

    M ẍ + K x = (F, 0),   M = diag(m₁, m₂),   K = [[k₁, −k₁], [−k₁, k₁ + k₂]].

The eigenvalues of M^{-1/2} K M^{-1/2} = [[a, b], [b, c]] (a = k₁/m₁, b = −k₁/√(m₁m₂),
c = (k₁ + k₂)/m₂) are λ₊ = (a + c)/2 + √(((a − c)/2)² + b²) and λ₋ = (ac − b²)/λ₊ =
k₁k₂/(m₁m₂λ₊) (the product of the roots: no cancellation for a soft base), with the
eigenvectors (b, λ − a); φ = M^{-1/2}v normalised to φᵀMφ = 1 gives the drive-point (screed)
receptance Σ_k φ_{1k}²/(ω_k² − ω²), i.e. two modes of modal mass m_k = 1/φ_{1k}² at the drive
point (Σ 1/m_k = 1/m₁). Each mode's loss factor is the strain-energy-weighted loss of the
springs (the modal strain energy method, Johnson & Kienholz, AIAA J. 20, 1982):
η_k = [η_layer k₁(φ_{1k} − φ_{2k})² + η_base k₂ φ_{2k}²]/ω_k² (0 for a rigid-body mode).

The mass–spring resonance of the screed on the layer over a rigid base,
f₀ = (1/2π)√(s′/m″), m″ = ρt, is the usual design figure (Vigran, *Building Acoustics*,
§8.3; Cremer, Heckl & Petersson §5.8): a soft layer (f₀ well below the ball's ~20 Hz
contact frequency) leaves the screed a free mass during the contact, a stiff one makes the
screed bounce on the layer within the contact.

**What reaches the slab** (``force_transmissibility``, used by the room chain,
``rbjax.room.chain``): a locally reacting screed of mass m″ per area on the layer
s̃′ = s′(1 + jη) over a heavy base passes the force

    F_slab(ω) = T(ω) F(ω),   T = s̃′/(s̃′ − ω²m″) = 1/(1 − (f/f₀)²/(1 + jη)),

so |T| = 1 well below f₀, |T|² = (1 + η²)/η² at f₀ and |T|² → (1 + η²)(f₀/f)⁴ above: the improvement
ΔL = 40 lg(f/f₀) that EN 12354-2:2000 / ISO 12354-2:2017 Annex C gives for floating floors of
asphalt or dry construction (locally reacting) and of Cremer, Heckl & Petersson's lumped floating
floor (*Structure-Borne Sound*, 3rd ed., §4.6 on elastic interlayers: the force transmissibility of
a mass on a spring); Vigran, *Building Acoustics*, §8.3. A screed that bends spreads the force over
an area that grows towards high frequencies: for wet (cement, calcium-sulphate) screeds Annex C
gives ΔL = 30 lg(f/f₀) instead, so T above is optimistic for them by up to 10 lg(f/f₀) dB. The
hysteretic loss (a frequency-independent η) is that of resilient materials; the area A and the base
mode do not enter T (a heavy base: the slab's point impedance ≫ ωm″A over the band).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..declare import NON_NEGATIVE, POSITIVE, Parameter
from .kinds import AbstractModalFloor, ModalFloor


class FloatingFloor(AbstractModalFloor):
    """A screed on a resilient layer over a one-mode base (module docstring): two modes at the
    drive point, computed from the declared parameters (traceable: the floor can be designed
    by gradient).

    Attributes:
        screed_thickness_m, screed_density_kg_per_m3: the screed (m″ = ρt).
        area_m2: the screed area that moves with the ball (m₁ = ρtA, k₁ = s′A).
        dynamic_stiffness_N_per_m3: s′ of the resilient layer (EN 29052-1).
        layer_loss_factor: η of the layer.
        base_mass_kg, base_frequency_Hz, base_loss_factor: the base structure's mode at the
            drive point (f₂ = 0: a free mass).
    """

    screed_thickness_m: ArrayLike
    screed_density_kg_per_m3: ArrayLike
    area_m2: ArrayLike
    dynamic_stiffness_N_per_m3: ArrayLike
    base_mass_kg: ArrayLike
    base_frequency_Hz: ArrayLike
    layer_loss_factor: ArrayLike = 0.1
    base_loss_factor: ArrayLike = 0.02
    name = "floating"
    PARAMETERS = {
        "screed_thickness_m": Parameter(
            "m", **POSITIVE, description="screed thickness t (m₁ = ρtA)"
        ),
        "screed_density_kg_per_m3": Parameter("kg/m^3", **POSITIVE, description="screed density ρ"),
        "area_m2": Parameter("m^2", **POSITIVE, description="screed area A moving with the ball"),
        "dynamic_stiffness_N_per_m3": Parameter(
            "N/m^3",
            **POSITIVE,
            description="dynamic stiffness s′ of the resilient layer (k₁ = s′A)",
        ),
        "base_mass_kg": Parameter(
            "kg", **POSITIVE, description="modal mass m₂ of the base at the drive point"
        ),
        "base_frequency_Hz": Parameter(
            "Hz", **NON_NEGATIVE, description="frequency f₂ of the base's mode (0: a free mass)"
        ),
        "layer_loss_factor": Parameter(
            "1", **NON_NEGATIVE, description="loss factor of the resilient layer"
        ),
        "base_loss_factor": Parameter(
            "1", **NON_NEGATIVE, description="loss factor of the base's spring"
        ),
    }

    @property
    def num_modes(self) -> int:
        return 2

    @property
    def screed_mass_kg(self):
        return self.screed_density_kg_per_m3 * self.screed_thickness_m * self.area_m2

    def modes(self):
        m1, m2 = (
            jnp.asarray(self.screed_mass_kg, dtype=jnp.float64),
            jnp.asarray(self.base_mass_kg, dtype=jnp.float64),
        )
        k1 = jnp.asarray(self.dynamic_stiffness_N_per_m3 * self.area_m2, dtype=jnp.float64)
        k2 = m2 * (2.0 * jnp.pi * self.base_frequency_Hz) ** 2
        a, b, c = k1 / m1, -k1 / jnp.sqrt(m1 * m2), (k1 + k2) / m2
        upper = 0.5 * (a + c) + jnp.sqrt((0.5 * (a - c)) ** 2 + b**2)
        lam = jnp.stack([k1 * k2 / (m1 * m2 * upper), upper])  # ω², ascending
        v1, v2 = b, lam - a  # eigenvectors (b, λ − a), b ≠ 0
        norm = jnp.sqrt(v1**2 + v2**2)
        phi1, phi2 = v1 / norm / jnp.sqrt(m1), v2 / norm / jnp.sqrt(m2)
        free = lam <= 0.0
        safe = jnp.where(free, 1.0, lam)
        strain = (
            self.layer_loss_factor * k1 * (phi1 - phi2) ** 2 + self.base_loss_factor * k2 * phi2**2
        )
        omega = jnp.where(free, 0.0, jnp.sqrt(safe))
        return 1.0 / phi1**2, omega, jnp.where(free, 0.0, strain / safe)

    @property
    def mass_kg(self):
        """The modal masses at the drive point, kg (as ``ModalFloor.mass_kg``)."""
        return self.modes()[0]

    @property
    def frequency_Hz(self):
        """The modes' frequencies, Hz (ascending; as ``ModalFloor.frequency_Hz``)."""
        return self.modes()[1] / (2.0 * jnp.pi)

    @property
    def loss_factor(self):
        """The modes' loss factors (as ``ModalFloor.loss_factor``)."""
        return self.modes()[2]

    @property
    def layer_resonance_Hz(self):
        """f₀ = (1/2π)√(s′/m″), m″ = ρt: the screed on the layer over a rigid base (EN 12354-2
        Annex C)."""
        return jnp.sqrt(
            self.dynamic_stiffness_N_per_m3
            / (self.screed_density_kg_per_m3 * self.screed_thickness_m)
        ) / (2.0 * jnp.pi)

    def force_transmissibility(self, freq_Hz):
        """T(f) = F_slab/F = 1/(1 − (f/f₀)²/(1 + jη)) of a locally reacting screed (module
        docstring); complex."""
        ratio = (jnp.asarray(freq_Hz, dtype=jnp.float64) / self.layer_resonance_Hz) ** 2
        return 1.0 / (1.0 - ratio / (1.0 + 1j * self.layer_loss_factor))

    def modal_floor(self) -> ModalFloor:
        """The same modes as a ``ModalFloor`` of static values (concrete parameters only)."""
        return ModalFloor(
            *(
                np.asarray(x, dtype=np.float64)
                for x in (self.mass_kg, self.frequency_Hz, self.loss_factor)
            )
        )
