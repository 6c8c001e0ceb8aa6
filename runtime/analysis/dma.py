"""A Prony series from dynamic mechanical analysis (DMA): storage and loss moduli against
frequency, fitted for ``kvrod calibrate --dma``.

Model (the uniaxial complex modulus of a generalized Maxwell solid whose branches all have
the equilibrium Poisson ratio, so that the rod's extension and bending carry exactly this
series, derivation step ``maxwell_rod``)::

    E'(omega)  = E_inf + sum_k E_k (omega theta_k)^2 / (1 + (omega theta_k)^2)
    E''(omega) =         sum_k E_k  omega theta_k    / (1 + (omega theta_k)^2)

The relaxation times ``theta_k`` are fixed, log-spaced over (and half a decade beyond)
the measured frequency range (``per_decade`` per decade, 3 by default: a single Debye
peak between two grid times is matched to ~0.7 %, with 2 per decade only to ~4 %); the
moduli ``E_inf, E_k >= 0`` enter linearly and are found by non-negative least squares
(:func:`scipy.optimize.nnls`) on the residuals relative to each measured modulus (E' and
E'' alike, each decade alike). The uncertainty of the moduli kept (``E_k > 0``) is the
linearised least-squares covariance ``s^2 (J^T J)^-1`` of the active set, ``s^2`` the
residual variance; a term whose 95 % interval reaches 0 is marked as not resolved by the
data.

Doubts (the fit is reported, and ``accepted`` is False): relative RMS residual above
``MAX_REL_RMS``; fewer data than parameters kept; non-positive, non-finite or unsorted
data are refused before fitting (the message names the row).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from runtime.analysis.records import load_csv

#: a fit with a relative RMS residual above this is doubtful (5 %)
MAX_REL_RMS = 0.05
#: accepted frequency column names (Hz, rad/s) and modulus columns (Pa)
FREQUENCY_COLUMNS = {"frequency_hz": 2 * math.pi, "omega": 1.0}
MODULUS_COLUMNS = ("storage", "loss")


@dataclass
class DmaFit:
    """A fitted Prony series (SI: Pa, s, rad/s) with its data and diagnostics."""

    omega: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    E_inf: float
    theta: np.ndarray           # the terms kept (E_k > 0)
    E: np.ndarray
    std_E_inf: float
    std_E: np.ndarray
    theta_grid: np.ndarray      # every time tried
    rel_rms: float
    poisson_ratio: float
    doubts: list[str] = field(default_factory=list)

    @property
    def accepted(self) -> bool:
        return not self.doubts

    def moduli(self, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(E', E'') of the fitted series at ``omega`` (rad/s)."""
        x = np.multiply.outer(np.asarray(omega, dtype=float), self.theta)
        return (self.E_inf + (x**2 / (1 + x**2)) @ self.E, (x / (1 + x**2)) @ self.E)

    def material(self, density: float) -> dict:
        """A ``[material]`` table for a problem file: the equilibrium spring and one branch
        per term, all with the data's Poisson ratio."""
        nu = self.poisson_ratio
        return {"model": "generalized_maxwell", "density": density,
                "youngs_modulus": self.E_inf, "poisson_ratio": nu,
                "branches": [{"youngs_modulus": float(e), "poisson_ratio": nu,
                              "tau": float(t)} for e, t in zip(self.E, self.theta,
                                                                strict=True)]}

    def summary(self) -> dict:
        return {"E_inf": self.E_inf, "std_E_inf": self.std_E_inf,
                "terms": [{"tau": float(t), "E": float(e), "std_E": float(s),
                           "resolved": bool(e - 1.96 * s > 0)}
                          for t, e, s in zip(self.theta, self.E, self.std_E, strict=True)],
                "relaxation_times_tried": self.theta_grid.tolist(),
                "relative_rms_residual": self.rel_rms, "poisson_ratio": self.poisson_ratio,
                "n_data": int(self.omega.size), "accepted": self.accepted,
                "doubts": self.doubts}


def load_dma(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read and check a DMA CSV.

    Parameters
    ----------
    path : str or Path
        CSV with a header naming ``frequency_hz`` (Hz) or ``omega`` (rad/s), ``storage``
        and ``loss`` (Pa).

    Returns
    -------
    omega, storage, loss : ndarray
        rad/s, Pa, Pa; frequencies strictly increasing, moduli finite (storage > 0,
        loss >= 0).

    Raises
    ------
    ValueError
        The message names the file, the row and the column of the first bad value.
    """
    path = Path(path)
    head = load_csv(path, ())  # existence, encoding and emptiness checks
    del head
    with path.open(encoding="utf-8") as fh:
        first = next((ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")), "")
    names = [c.strip().lower() for c in first.split(",")]
    freq = [c for c in FREQUENCY_COLUMNS if c in names]
    if len(freq) != 1:
        raise ValueError(f"data file {str(path)!r} needs one frequency column, "
                         f"'frequency_hz' (Hz) or 'omega' (rad/s); columns: {', '.join(names)}")
    f, Ep, Epp = load_csv(path, (freq[0], *MODULUS_COLUMNS))
    omega = f * FREQUENCY_COLUMNS[freq[0]]
    # the file's line of each data row and its cells (load_csv skips comments and blanks)
    import csv

    rows = [(i, r) for i, r in enumerate(csv.reader(path.read_text(encoding="utf-8")
                                                    .splitlines()), 1)
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")][1:]
    for name, v in ((freq[0], f), ("storage", Ep), ("loss", Epp)):
        bad = np.flatnonzero(~np.isfinite(v) | (v <= 0) if name != "loss"
                             else ~np.isfinite(v) | (v < 0))
        if bad.size:
            k = int(bad[0])
            line, cells = rows[k] if k < len(rows) else (k + 2, [])
            col = names.index(name)
            text = cells[col].strip() if col < len(cells) else ""
            shown = (f"{float(v[k]):g}" if np.isfinite(v[k]) else
                     f"{text!r} (not a finite number)" if text else "missing")
            raise ValueError(f"data file {str(path)!r}: line {line}: {name} = {shown} is "
                             f"outside the allowed range: a finite number "
                             f"{'>= 0' if name == 'loss' else '> 0'}")
    if omega.size < 3:
        raise ValueError(f"data file {str(path)!r} has {omega.size} rows; a fit needs at "
                         "least 3 frequencies")
    if np.any(np.diff(omega) <= 0):
        k = int(np.flatnonzero(np.diff(omega) <= 0)[0]) + 1
        line = rows[k][0] if k < len(rows) else k + 2
        raise ValueError(f"data file {str(path)!r}: line {line}: the frequencies must "
                         f"increase strictly ({float(f[k - 1]):g} then {float(f[k]):g})")
    span = math.log10(omega.max()) - math.log10(omega.min())
    if span > 30:
        raise ValueError(f"data file {str(path)!r}: the frequencies span {span:.3g} decades "
                         f"({float(f.min()):g} ... {float(f.max()):g}); at most 30 "
                         "(check the units of the frequency column)")
    return omega, Ep, Epp


def fit_prony(omega: np.ndarray, storage: np.ndarray, loss: np.ndarray, *,
              poisson_ratio: float, per_decade: float = 3.0) -> DmaFit:
    """Fit the Prony series (see the module docstring) to E'(omega), E''(omega).

    Parameters
    ----------
    omega, storage, loss : ndarray
        Angular frequencies (rad/s) and the storage and loss moduli there (Pa).
    poisson_ratio : float
        Poisson's ratio of every branch (a uniaxial test does not measure it).
    per_decade : float
        Relaxation times per decade of the grid.

    Returns
    -------
    DmaFit
        E_inf and the terms kept with their standard errors, the relative RMS residual
        and ``doubts`` (``accepted`` is False when there are any).
    """
    from scipy.optimize import nnls

    omega = np.asarray(omega, dtype=float)
    storage = np.asarray(storage, dtype=float)
    loss = np.asarray(loss, dtype=float)
    if not per_decade > 0:
        raise ValueError(f"per_decade = {float(per_decade):g} is outside the allowed range: "
                         "> 0")
    lo, hi = math.log10(1.0 / omega.max()) - 0.5, math.log10(1.0 / omega.min()) + 0.5
    n_terms = max(1, int(round((hi - lo) * per_decade)) + 1)
    theta = np.logspace(lo, hi, n_terms)
    x = np.multiply.outer(omega, theta)
    # relative residuals of each modulus (the loss is often two decades below the
    # storage modulus; weighting both by |E*| would leave it unfitted)
    w_loss = 1.0 / np.where(loss > 0, loss, np.hypot(storage, loss))
    A = np.vstack([np.column_stack([np.ones_like(omega), x**2 / (1 + x**2)]),
                   np.column_stack([np.zeros_like(omega), x / (1 + x**2)])])
    b = np.concatenate([storage, loss])
    W = np.concatenate([1.0 / storage, w_loss])
    coef, _ = nnls(A * W[:, None], b * W, maxiter=50 * A.shape[1])
    res = (A @ coef - b) * W
    keep = np.flatnonzero(coef[1:] > 0) + 1
    cols = np.concatenate([[0], keep])
    Aw = (A * W[:, None])[:, cols]
    dof = max(b.size - cols.size, 1)
    s2 = float(res @ res) / dof
    try:
        cov = s2 * np.linalg.inv(Aw.T @ Aw)
        std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        std = np.full(cols.size, math.inf)
    rel_rms = float(np.sqrt(np.mean(res**2)))
    doubts = []
    if rel_rms > MAX_REL_RMS:
        doubts.append(f"relative RMS residual {rel_rms:.3g} above {MAX_REL_RMS} (the data "
                      "are not a Prony series with these times: too few per decade, or "
                      "noise)")
    if b.size <= cols.size:
        doubts.append(f"{b.size} data for {cols.size} parameters")
    return DmaFit(omega=omega, storage=storage, loss=loss, E_inf=float(coef[0]),
                  theta=theta[keep - 1], E=coef[keep], std_E_inf=float(std[0]),
                  std_E=std[1:], theta_grid=theta, rel_rms=rel_rms,
                  poisson_ratio=float(poisson_ratio), doubts=doubts)
