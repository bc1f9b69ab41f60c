"""Tresca plasticity (a clay's undrained strength): the return mapping in principal stresses,
to the main plane or to a corner of the hexagon, and its consistent tangent.

Yield function (de Souza Neto, Peric & Owen 2008, sec. 8.1; principal stresses ordered
``s1 >= s2 >= s3``, tension positive):

    f = s1 - s3 - sigma_y(kappa) <= 0,   sigma_y = 2 k + H kappa,

``k`` the shear strength (the undrained cohesion ``c_u``), ``2 k`` the uniaxial (unconfined)
strength, ``H`` a linear hardening modulus of the uniaxial strength (as
:class:`ssw.constitutive.von_mises.VonMises`'s), ``kappa`` the work-conjugate equivalent
plastic strain (``sigma_y d kappa = sigma : d eps_p``; the axial plastic strain in a uniaxial
test). Flow is associated: ``d eps_p = d gamma (e1 e1 - e3 e3)`` on the main plane, the sum
of the two planes' normals at a corner; it keeps the volume, so the mean stress is elastic.

Return mapping (backward Euler, closed form for linear hardening; de Souza Neto et al.
2008, Boxes 8.1-8.3) from the trial's principal stresses ``s_tr``:

* main plane (region 1): ``d gamma = f_tr / (4 G + H)``, ``s = s_tr - 2 G d gamma a``,
  ``a = (1, 0, -1)``; valid while the order ``s1 >= s2 >= s3`` holds;
* right corner (region 2, ``s2 = s3``: triaxial tension) when ``s1_tr + s3_tr - 2 s2_tr >=
  0``, else the left corner (region 3, ``s1 = s2``: triaxial compression, the axis under an
  indenter): two planes ``a`` and ``b = (1, -1, 0)`` (right) or ``(0, 1, -1)`` (left),

      [[4 G + H, 2 G + H], [2 G + H, 4 G + H]] (d gamma_a, d gamma_b) = (f_a_tr, f_b_tr),
      s = s_tr - 2 G (d gamma_a a + d gamma_b b),   d kappa = d gamma_a + d gamma_b.

Axisymmetric principal frame. The hoop stress is principal; the others are the eigenvalues of
the (rr, zz, rz) block, ``m +- r`` with ``m = (s_rr + s_zz) / 2``, ``r = hypot((s_rr -
s_zz) / 2, s_rz)``, eigenvector angle ``theta``, ``tan 2 theta = 2 s_rz / (s_rr - s_zz)``.
In Mandel form the eigenprojections ``E_A, E_B, E_t`` and the in-plane spin direction
``M = (v_A v_B + v_B v_A) / sqrt(2)`` are an orthonormal basis of the 4-vectors.

Consistent tangent (the derivative of an isotropic tensor function; de Souza Neto et al.
2008, app. A.1-A.2):

    D = sum_ij (d s_i / d e_j) E_i E_j^T + (s_A - s_B) / (e_A - e_B) M M^T,

``e`` the trial's principal elastic strains (``e_A - e_B = r_tr / G``), ``d s / d e = (d s /
d s_tr) (lambda 1 1^T + 2 G I)`` the principal-space tangent; for ``e_A = e_B`` the spin
coefficient is its limit ``d s_A / d e_A - d s_A / d e_B``. Elastic: ``K ONE ONE^T + 2 G
P_DEV``. Associated flow: ``D`` is symmetric.

References
----------
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley, sec. 8.1 (Boxes 8.1-8.3) and app. A.
Tresca, H. (1864). Sur l'ecoulement des corps solides soumis a de fortes pressions.
*C. R. Acad. Sci. Paris* 59, 754-758.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.constitutive.base import YIELD_RTOL, Update, check_stress, number_text
from ssw.constitutive.tensors import ONE, P_DEV, SQRT2, bulk_shear, elastic_tangent

#: The in-plane eigenvalues count as equal (the spin coefficient's limit) below this share of
#: the stress scale.
EQUAL_RTOL = 1e-10
#: Normals (principal space, ordered) of the main plane and of the right and left corners'
#: second planes.
PLANE_A = np.array([1.0, 0.0, -1.0])
PLANE_RIGHT = np.array([1.0, -1.0, 0.0])
PLANE_LEFT = np.array([0.0, 1.0, -1.0])


def principal_frame(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                 np.ndarray]:
    """The principal frame of axisymmetric tensors (n, 4) (Mandel; module docstring).

    Parameters
    ----------
    stress : numpy.ndarray
        Axisymmetric tensors (Mandel), (n, 4).

    Returns
    -------
    basis : (n, 3, 4) the eigenprojections ``E_A, E_B, E_t`` (A: the larger in-plane
        eigenvalue).
    spin : (n, 4) the unit in-plane spin direction ``M``.
    values : (n, 3) the eigenvalues ``(m + r, m - r, s_tt)``.
    r : (n,) half the in-plane eigenvalue gap.
    """
    a, b = stress[:, 0], stress[:, 1]
    c = stress[:, 3] / SQRT2
    half = 0.5 * (a - b)
    r = np.hypot(half, c)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos2 = np.where(r > 0, half / r, 1.0)
        sin2 = np.where(r > 0, c / r, 0.0)
    n = stress.shape[0]
    basis = np.zeros((n, 3, 4))
    basis[:, 0, 0] = basis[:, 1, 1] = 0.5 * (1.0 + cos2)
    basis[:, 0, 1] = basis[:, 1, 0] = 0.5 * (1.0 - cos2)
    basis[:, 0, 3] = sin2 / SQRT2
    basis[:, 1, 3] = -sin2 / SQRT2
    basis[:, 2, 2] = 1.0
    spin = np.stack([-sin2 / SQRT2, sin2 / SQRT2, np.zeros(n), cos2], axis=1)
    m = 0.5 * (a + b)
    values = np.stack([m + r, m - r, stress[:, 2]], axis=1)
    return basis, spin, values, r


@dataclass(frozen=True)
class Tresca:
    """Tresca plasticity (module docstring).

    Parameters
    ----------
    cohesion : float
        The shear strength ``k``, Pa (the undrained cohesion ``c_u``), ``> 0``.
    hardening : float
        ``H = d sigma_y / d kappa`` of the uniaxial strength, Pa (>= 0; 0: perfectly
        plastic).
    """

    cohesion: float
    hardening: float = 0.0
    name: ClassVar[str] = "tresca"
    #: plastic flow keeps the volume (the contact solver's mixed u-p form is then exact)
    isochoric: ClassVar[bool] = True

    def __post_init__(self) -> None:
        check_stress(self, "cohesion", "a shear strength k > 0 Pa")
        check_stress(self, "hardening", "a hardening modulus >= 0 Pa", zero=True)

    @property
    def key(self) -> str:
        """Short file-name-safe text that tells two models apart (enters the scene id)."""
        text = f"tresca-k{number_text(self.cohesion, 1e3)}kPa"
        if self.hardening:
            text += f"-H{number_text(self.hardening, 1e6)}MPa"
        return text

    @property
    def strength(self) -> float:
        """The unconfined (uniaxial) strength ``2 k``, Pa."""
        return 2.0 * float(self.cohesion)

    def params(self) -> dict[str, Any]:
        """The model's parameters as a plain dict (SI units, angles in degrees).

        Returns
        -------
        dict
            ``model`` (the registry name) and each parameter.
        """
        return {"model": self.name, "cohesion": self.cohesion, "hardening": self.hardening}

    def update(self, E: float, nu: float, strain: np.ndarray, state: np.ndarray) -> Update:
        """Return mapping of ``strain`` (n, 4) from ``state`` (n, 5) (module docstring).

        Parameters
        ----------
        E : float
            Young's modulus of the sample (Pa).
        nu : float
            Poisson's ratio of the sample, in (-1, 0.5).
        strain : numpy.ndarray
            Total strains (Mandel), (n, 4).
        state : numpy.ndarray
            State at the increment's start, (n, 5): plastic strain and hardening variable.

        Returns
        -------
        Update
            Stress (Pa), consistent tangent (Pa), new state, yield flags and return regions.

        Raises
        ------
        ConfigError
            If ``E`` is not > 0 or ``nu`` lies outside (-1, 0.5).
        """
        K, G = bulk_shear(E, nu)
        H = float(self.hardening)
        Ce = elastic_tangent(K, G)
        strain = np.asarray(strain, float)
        sig_tr = (strain - state[:, :4]) @ Ce
        basis, spin, values, r = principal_frame(sig_tr)
        order = np.argsort(-values, axis=1, kind="stable")
        inv = np.argsort(order, axis=1)
        s_tr = np.take_along_axis(values, order, axis=1)  # s1 >= s2 >= s3
        sy = 2.0 * self.cohesion + H * state[:, 4]
        f = s_tr[:, 0] - s_tr[:, 2] - sy
        yl = f > YIELD_RTOL * 2.0 * self.cohesion
        f = np.where(yl, f, 0.0)
        # one-vector return to the main plane (Box 8.1)
        P, Q = 4.0 * G + H, 2.0 * G + H
        g = f / P
        s_main = s_tr - 2.0 * G * g[:, None] * PLANE_A
        slack = 1e-10 * (s_tr[:, 0] - s_tr[:, 2])
        main = ((s_main[:, 0] + slack >= s_main[:, 1])
                & (s_main[:, 1] + slack >= s_main[:, 2]))
        # two-vector returns to the right (s2 = s3) or left (s1 = s2) corner (Boxes 8.2-8.3)
        right = s_tr[:, 0] + s_tr[:, 2] - 2.0 * s_tr[:, 1] >= 0.0
        b = np.where(right[:, None], PLANE_RIGHT, PLANE_LEFT)
        fb = np.where(yl, np.einsum("ni,ni->n", b, s_tr) - sy, 0.0)
        det = P * P - Q * Q
        ga, gb = (P * f - Q * fb) / det, (P * fb - Q * f) / det
        s_corner = s_tr - 2.0 * G * (ga[:, None] * PLANE_A + gb[:, None] * b)
        region = np.where(~yl, 0, np.where(main, 1, np.where(right, 2, 3))).astype(np.int8)
        on_main, corner = region == 1, region >= 2
        s = np.where(on_main[:, None], s_main, np.where(corner[:, None], s_corner, s_tr))
        dkappa = np.where(on_main, g, np.where(corner, ga + gb, 0.0))
        # principal-space tangent d s / d s_tr (ordered)
        n = strain.shape[0]
        Ds = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        Ds[on_main] -= (2.0 * G / P) * np.outer(PLANE_A, PLANE_A)
        bc = b[corner]
        dga = (P * PLANE_A - Q * bc) / det
        dgb = (P * bc - Q * PLANE_A) / det
        Ds[corner] -= 2.0 * G * (PLANE_A[None, :, None] * dga[:, None, :]
                                 + bc[:, :, None] * dgb[:, None, :])
        lam = K - 2.0 * G / 3.0
        Ds = Ds @ (lam * np.ones((3, 3)) + 2.0 * G * np.eye(3))  # d s / d e (principal)
        # back to the frame's order (A, B, t)
        rows = np.take_along_axis(Ds, inv[:, :, None], axis=1)
        Dp = np.take_along_axis(rows, inv[:, None, :], axis=2)
        sp = np.take_along_axis(s, inv, axis=1)
        tiny = r <= EQUAL_RTOL * np.maximum(np.max(np.abs(values), axis=1), sy)
        with np.errstate(invalid="ignore", divide="ignore"):
            coef = np.where(tiny, Dp[:, 0, 0] - Dp[:, 0, 1], G * (sp[:, 0] - sp[:, 1]) / r)
        D = np.einsum("nia,nij,njb->nab", basis, Dp, basis)
        D += coef[:, None, None] * spin[:, :, None] * spin[:, None, :]
        stress = np.where(yl[:, None], np.einsum("ni,nia->na", sp, basis), sig_tr)
        tangent = np.where(yl[:, None, None], D, Ce)
        new = state.copy()
        elastic = (stress @ ONE)[:, None] * ONE / (9.0 * K) + (stress @ P_DEV) / (2.0 * G)
        new[:, :4] = np.where(yl[:, None], strain - elastic, state[:, :4])
        new[:, 4] += dkappa
        return Update(stress, tangent, new, yl, region)

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """``(s1 - s3) / (2 k + H kappa)`` (n,).

        Parameters
        ----------
        stress : numpy.ndarray
            Stresses (Mandel, Pa), (n, 4).
        state : numpy.ndarray
            States, (n, 5) (column 4: the hardening variable).

        Returns
        -------
        numpy.ndarray
            Yield ratio, (n,): 1 on the yield surface, below 1 inside.
        """
        values = principal_frame(np.asarray(stress, float))[2]
        return (values.max(axis=1) - values.min(axis=1)) / (
            2.0 * self.cohesion + self.hardening * state[:, 4])


__all__ = ["Tresca", "principal_frame"]
