"""State-space realizations of ``B(q)/F(q)`` and observer gains (thesis section 3.1, appendix D).

* :func:`modal_realization` — real block-diagonal form from the partial fractions (well
  conditioned for lightly damped poles near z = 1, unlike companion forms);
* :func:`balanced_realization` — square-root balancing of it (what the observers use);
* :func:`observer_gain` — the gain ``L`` and the poles of ``A - L C``;
* :class:`ModalFilter` — ``A - L C`` run as decoupled first-order modes (compiled loop).

Observer gain (pole choice). ``poles`` may be

* ``"model"`` (default): ``L = 0``; the error dynamics are the model's own (stable) poles.
  The residual is then ``y - g(model response to the train)`` and white measurement noise
  passes with gain 1 (the smallest possible here).
* ``"contracted"``: the model poles scaled by ``contraction`` (default 0.95) towards the
  origin, placed with python-control ``place`` (Tits-Yang robust pole placement, not
  Ackermann).
* an array of poles (discrete time, |p| < 1), placed the same way.

The thesis' appendix D poles (near the origin, Ackermann) amplified white measurement noise
43-96 times in the feasibility study (``shared/diagnosis-notes.md``); the project defaults to
``L = 0`` and measures the noise gain of whatever is chosen
(:attr:`bearing_observer.observer.FaultObserver.noise_gain`).
Every gain is checked: that all eigenvalues of ``A - L C`` lie strictly inside the unit
circle (ValueError otherwise).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import linalg, signal


class ModalFilter:
    """The observer's error dynamics as decoupled first-order modes (exact state).

    ``x[n+1] = Ao x[n] + Bw w[n] + Bz z[n]``, ``out[n] = C x[n] + D w[n]`` with
    ``Ao = V diag(lam) V^-1``: each mode ``xi_i[n+1] = lam_i xi_i[n] + v_i[n]`` (one complex
    mode per conjugate pair) runs in the compiled :func:`run_modes`,
    its state carried between calls. No transfer-function polynomials are formed (they are
    badly conditioned for poles near z = 1).
    """

    def __init__(self, Ao, Bw, Bz, C, D):
        lam, V = linalg.eig(Ao)
        if np.linalg.cond(V) > 1e10:
            raise ValueError("observer poles give a nearly defective A - L C; choose distinct poles")
        Vi = linalg.inv(V)
        keep = lam.imag >= 0.0
        self.lam = np.ascontiguousarray(lam[keep])
        self.weight = np.where(self.lam.imag > 0.0, 2.0, 1.0)
        self.bw = np.ascontiguousarray((Vi @ Bw)[keep, 0])
        self.bz = np.ascontiguousarray((Vi @ Bz)[keep, 0])
        self.c = np.ascontiguousarray((C @ V)[0, keep])
        self.d = float(D[0, 0])
        self.reset()

    def reset(self):
        self.state = np.zeros(self.lam.size, dtype=complex)

    def run(self, w: np.ndarray, z: np.ndarray) -> np.ndarray:
        out = np.empty(w.size)
        run_modes(self.lam, self.bw, self.bz, self.c, self.weight, self.d,
                  np.ascontiguousarray(w, dtype=float), np.ascontiguousarray(z, dtype=float),
                  self.state, out)
        return out


def modal_realization(b, f):
    """Real block-diagonal (modal) realization of ``B(q)/F(q)`` from its partial fractions.

    Well conditioned for lightly damped poles near z = 1, unlike companion forms. Needs
    distinct poles and ``len(b) <= len(f)``; raises ValueError otherwise.
    """
    b = np.asarray(b, dtype=float)
    f = np.asarray(f, dtype=float)
    if b.size > f.size:
        raise ValueError("modal realization needs nb <= nf + 1")
    r, p, k = signal.residuez(b, f)
    d = float(np.real(np.sum(r))) + (float(np.real(k[0])) if len(k) else 0.0)
    blocks, bs, cs = [], [], []
    used = np.zeros(p.size, dtype=bool)
    for i in range(p.size):
        if used[i]:
            continue
        used[i] = True
        if abs(p[i].imag) <= 1e-12 * max(1.0, abs(p[i])):
            blocks.append(np.array([[p[i].real]]))
            bs.append([1.0])
            cs.append([float(np.real(r[i] * p[i]))])
            continue
        j = np.flatnonzero(~used & (np.abs(p - np.conj(p[i])) < 1e-8 * max(1.0, abs(p[i]))))
        if j.size == 0:
            raise ValueError("unpaired complex pole")
        used[j[0]] = True
        pi = p[i] if p[i].imag > 0 else np.conj(p[i])
        ci = (r[i] if p[i].imag > 0 else r[j[0]]) * pi
        blocks.append(np.array([[pi.real, -pi.imag], [pi.imag, pi.real]]))
        bs.append([1.0, 0.0])
        cs.append([2.0 * ci.real, -2.0 * ci.imag])
    A = linalg.block_diag(*blocks)
    B = np.concatenate(bs)[:, None]
    C = np.concatenate(cs)[None, :]
    return A, B, C, np.array([[d]])


def balanced_realization(b, f):
    """Balanced state-space realization ``(A, B, C, D)`` of ``B(q)/F(q)`` (q^-1 polynomials).

    Square-root balancing (discrete gramians) of the modal realization; when balancing is
    not possible (singular gramians), the modal realization itself is returned, and when
    that is not possible either, ``scipy.signal.tf2ss``'s companion form.
    """
    try:
        A, B, C, D = modal_realization(b, f)
    except ValueError:
        bb = np.asarray(b, dtype=float)
        ff = np.asarray(f, dtype=float)
        m = max(bb.size, ff.size)
        A, B, C, D = signal.tf2ss(np.concatenate([bb, np.zeros(m - bb.size)]),
                                  np.concatenate([ff, np.zeros(m - ff.size)]))
        return A, B, C, D
    if A.shape[0] == 0:
        return A, B, C, D
    try:
        wc = linalg.solve_discrete_lyapunov(A, B @ B.T)
        wo = linalg.solve_discrete_lyapunov(A.T, C.T @ C)
        lc = linalg.cholesky((wc + wc.T) / 2, lower=True)
        lo = linalg.cholesky((wo + wo.T) / 2, lower=True)
        u, s, vt = linalg.svd(lo.T @ lc)
        if s.min() <= 1e-12 * s.max():
            raise linalg.LinAlgError("near non-minimal")
        sh = 1.0 / np.sqrt(s)
        T = lc @ vt.T * sh[None, :]
        Ti = (sh[:, None] * u.T) @ lo.T
        return Ti @ A @ T, Ti @ B, C @ T, D
    except (linalg.LinAlgError, ValueError):
        return A, B, C, D


def observer_gain(A, C, poles="model", contraction: float = 0.95):
    """Observer gain ``L`` (n×1) and the poles of ``A - L C``.

    Parameters
    ----------
    A : ndarray (n, n); C : ndarray (1, n)
    poles : "model" | "contracted" | array_like
        See the module docstring.
    contraction : float
        Factor for ``"contracted"`` (0 < contraction < 1).

    Raises
    ------
    ValueError
        Unknown choice, or some eigenvalue of ``A - L C`` not strictly inside |z| < 1.
    """
    n = A.shape[0]
    if isinstance(poles, str):
        if poles == "model":
            L = np.zeros((n, 1))
        elif poles == "contracted":
            if not 0.0 < contraction < 1.0:
                raise ValueError("contraction must lie in (0, 1)")
            L = _place(A, C, contraction * np.linalg.eigvals(A))
        else:
            raise ValueError(f"poles must be 'model', 'contracted' or an array, got {poles!r}")
    else:
        p = np.asarray(poles, dtype=complex).ravel()
        if p.size != n:
            raise ValueError(f"need {n} poles, got {p.size}")
        L = _place(A, C, p)
    eig = np.linalg.eigvals(A - L @ C)
    if n and np.max(np.abs(eig)) >= 1.0 - 1e-9:
        raise ValueError(f"observer unstable: max |eig(A - L C)| = {np.max(np.abs(eig)):.6f} >= 1")
    return L, eig


def _place(A, C, p):
    import control  # python-control: place() is Tits-Yang robust pole placement

    if np.any(np.abs(p) >= 1.0):
        raise ValueError("requested observer poles must lie strictly inside the unit circle")
    return np.asarray(control.place(A.T, C.T, p)).T


# compiled inner loop (numba; strict IEEE arithmetic, no fastmath)
@njit(cache=True)
def run_modes(lam: np.ndarray, bw: np.ndarray, bz: np.ndarray, c: np.ndarray,
              weight: np.ndarray, d: float, w: np.ndarray, z: np.ndarray,
              state: np.ndarray, out: np.ndarray) -> None:
    """Two-input LTI filter in modal form, state carried in ``state``.

    Per mode ``m``: ``xi_m[n+1] = lam[m] xi_m[n] + bw[m] w[n] + bz[m] z[n]``; output
    ``out[n] = d w[n] + sum_m weight[m] Re(c[m] xi_m[n])`` (one complex mode stands for a
    conjugate pair with ``weight`` 2).

    Parameters
    ----------
    lam, bw, bz, c : ndarray of complex, shape (M,)
        Mode poles, input and output coefficients.
    weight : ndarray, shape (M,)
        1 for real modes, 2 for conjugate pairs.
    d : float
        Direct feed-through of ``w``.
    w, z : ndarray, shape (n,)
        The two inputs.
    state : ndarray of complex, shape (M,)
        Mode states at the first sample; updated in place to the state after the last.
    out : ndarray, shape (n,)
        Output, written in place.
    """
    for i in range(w.size):
        acc = d * w[i]
        for m in range(lam.size):
            s = state[m]
            acc += weight[m] * (c[m] * s).real
            state[m] = lam[m] * s + bw[m] * w[i] + bz[m] * z[i]
        out[i] = acc
