"""Linearised photoclinometry by sparse least squares (registry name ``"photoclinometry"``).

The image's shading model ``I ~ a + b . grad z`` (paper eq. 3.5) is calibrated on the samples
(:mod:`.calibration`); then the correction ``d = z - z_lin`` to the linear reconstruction
solves, over every cell at once,

    min  sum_valid (u . grad d - r)^2 + lam_t sum (t . grad d)^2 + lam_r sum d^2
         + w_a sum_samples d^2

with ``u = b / |b|``, ``t`` across it, ``r = p_s - u . grad z_lin`` the slope along the light
that the image adds to the linear reconstruction's (``p_s = clip((I_smooth - a) / (g |b|))``
as in :mod:`.shading`), ``grad`` central differences with mirrored edges. The ridge
``lam_r`` and the cross-sun term ``lam_t`` are what make it well posed: without them every sun
line floats between the anchors (``docs/reconstruction.md``: 3-8x worse than linear at 1/256;
here the exact re-anchoring below limits the damage, but CG then needs several times the
iterations). The ridge scales with the sample pitch, ``lam_r = ridge / pitch^2`` (the
correction decays over about a pitch); a fixed ``lam_r = 0.002`` made the result 0.45x of
linear at 1/64 on a quarter-scale aerial_1 render. The defaults (ridge 1, cross-sun 0.05,
anchors 1, slope equations of weight 1) were set on that render (Oren-Nayar, 12-bit sensor)
and checked on an aerial_3 one (``docs/reconstruction.md``).
The normal equations (a 9-point scipy.sparse CSR matrix, assembled in one compiled pass) are
solved by conjugate gradients, preconditioned by the operator's cosine-diagonal part (the
mirror-averaged inverse of ``D^T (u u^T + lam_t t t^T) D + lam_r + w_a k / N``, two DCTs per
iteration). The result is
re-anchored exactly on the samples and blended as in :mod:`.shading`:
``z = z_lin + gamma * hull * (d - linear_interp(d at the samples))`` with the same fallback
rule for ``gamma``, capped by the same held-out check (option ``heldout_check``, on by default;
:func:`simlunar.reconstruction.heldout.heldout_gamma`): every fifth sample is left out, ``d`` is
solved again anchored on the others, and its least-squares weight on the left-out samples caps
``gamma``. Without the check the sun image alone made 0.77x / 0.94x linear's samples on the
full-resolution aerial_1 / aerial_2 (30 deg sun, 5 terrain seeds), where albedo passes the
explained-variance share; the check costs a second solve.

The project measured this family (``docs/reconstruction.md``, "Measured numbers"): 1.37x /
1.75x fewer samples than linear for equal MSE on aerial_1 / aerial_3, but 0.82x on the
moonyard under a 75 deg sun (harmful at high sun), against 1.73x / 2.37x / 1.12x for the
integrated slope of :mod:`.shading`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.fft as sfft
from scipy import ndimage, sparse
from scipy.sparse import linalg as splinalg

from simlunar.reconstruction._anchor import linear_field
from simlunar.reconstruction._reading import READING_OPTIONS, ReadingChecks
from simlunar.reconstruction.base import Guide, Reconstructed
from simlunar.reconstruction.calibration import calibrate
from simlunar.reconstruction.heldout import checked_blend
from simlunar.reconstruction.integrate import central_gradient, fft_workers
from simlunar.reconstruction.shading import ShadingOptions, fallback_gamma, shading_frames
from simlunar.registry import option, shared_option

__all__ = [
    "PhotoclinometryOptions",
    "central_difference_matrices",
    "normal_equations",
    "photoclinometry",
]


@dataclass(frozen=True)
class PhotoclinometryOptions(ReadingChecks):
    """Options of the sparse least-squares photoclinometry (:func:`photoclinometry`)."""

    ridge: float = option(
        1.0,
        doc="pull of the correction towards 0, in units of 1 / pitch^2: lam_r = ridge / pitch^2 "
        "(the correction decays over about a sample pitch)",
        gt=0,
        le=1e4,
    )
    across_weight: float = option(
        0.05, doc="lam_t: smoothness of the correction across the light", ge=0, le=100
    )
    anchor_weight: float = option(1.0, doc="w_a: weight of the samples", gt=0, le=1e6)
    rtol: float = option(3e-3, doc="relative residual at which CG stops", gt=0, lt=1)
    max_iter: int = option(300, doc="most CG iterations", ge=1, le=100000)
    gain: float = shared_option(READING_OPTIONS, "gain")
    clip: float = shared_option(READING_OPTIONS, "clip")
    image_sigma: float = shared_option(READING_OPTIONS, "image_sigma")
    gamma_max: float = option(1.0, doc="weight of the correction at full share", ge=0, le=1)
    share_lo: float = shared_option(READING_OPTIONS, "share_lo")
    share_hi: float = shared_option(READING_OPTIONS, "share_hi")
    use_flat: bool = shared_option(READING_OPTIONS, "use_flat")
    flat_guard: float = option(
        0.05, doc="flat pixels under this fraction of its median are left out", gt=0, lt=1
    )
    sigma_pitch: float = shared_option(READING_OPTIONS, "sigma_pitch")
    shadow: float = shared_option(READING_OPTIONS, "shadow")
    saturation: float = shared_option(READING_OPTIONS, "saturation")
    shadow_lit: float = shared_option(READING_OPTIONS, "shadow_lit")
    detail_clip: float = shared_option(READING_OPTIONS, "detail_clip")
    heldout_check: bool = option(
        True,
        doc="cap gamma by a check on held-out samples, as the shading reconstruction's: every "
        "fifth sample is left out, the correction is solved again from the others, and its "
        "weight that best predicts the left-out samples caps gamma",
        choices=(True, False),
    )

    def shading(self) -> ShadingOptions:
        """The shared reading of the image (frames, calibration, slopes, fallback)."""
        return ShadingOptions(
            gain=self.gain, clip=self.clip, image_sigma=self.image_sigma,
            gamma_max=self.gamma_max, share_lo=self.share_lo, share_hi=self.share_hi,
            use_flat=self.use_flat, use_others=False, flat_guard=self.flat_guard,
            sigma_pitch=self.sigma_pitch, shadow=self.shadow, saturation=self.saturation,
            shadow_lit=self.shadow_lit,
        )  # fmt: skip


def _central_1d(n: int) -> sparse.csr_matrix:
    """(n, n) central differences with mirrored ends (:func:`.integrate.central_gradient`)."""
    if n == 1:
        return sparse.csr_matrix((1, 1))
    d = sparse.diags([np.full(n - 1, 0.5), np.full(n - 1, -0.5)], [1, -1], format="lil")
    d[0, 0] = -0.5
    d[n - 1, n - 1] = 0.5
    return d.tocsr()


def central_difference_matrices(shape) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
    """Sparse d/d row and d/d col on a row-major flattened (rows, cols) grid.

    ``D_r @ z.ravel()`` equals ``central_gradient(z)[0].ravel()`` (and ``D_c`` the second).
    """
    rows, cols = (int(s) for s in shape)
    d_r = sparse.kron(_central_1d(rows), sparse.identity(cols), format="csr")
    d_c = sparse.kron(sparse.identity(rows), _central_1d(cols), format="csr")
    return d_r, d_c


_SLOTS = [(dr, dc) for dr in range(-2, 3) for dc in range(-2, 3) if abs(dr) + abs(dc) <= 2]
_SLOT = np.full((5, 5), -1, dtype=np.int64)
for _i, (_dr, _dc) in enumerate(_SLOTS):
    _SLOT[_dr + 2, _dc + 2] = _i
_SLOT_DR = np.array([d[0] for d in _SLOTS], dtype=np.int64)
_SLOT_DC = np.array([d[1] for d in _SLOTS], dtype=np.int64)


@numba.njit(cache=True, nogil=True)
def _assemble(
    rows, cols, u_r, u_c, t_r, t_c, lam_t, w, diag, resid, slot, sdr, sdc
):  # pragma: no cover - compiled
    """CSR arrays of ``D_u^T W D_u + lam_t D_t^T D_t + diag`` and ``D_u^T (w resid)``.

    Each equation row (a cell) of ``a D_r + b D_c`` touches four cells (rows r +- 1 and
    columns c +- 1, clamped: the mirrored central difference); its outer product adds to at
    most 13 neighbours (|dr| + |dc| <= 2) of each of them.
    """
    n = rows * cols
    vals = np.zeros((n, sdr.shape[0]))
    rhs = np.zeros(n)
    er = np.empty(4, np.int64)
    ec = np.empty(4, np.int64)
    ev = np.empty(4)
    for pass_ in range(2):
        a, b = (u_r, u_c) if pass_ == 0 else (t_r, t_c)
        for r in range(rows):
            for c in range(cols):
                j = r * cols + c
                wt = w[j] if pass_ == 0 else lam_t
                if wt == 0.0:
                    continue
                m = 0
                if rows > 1:
                    er[m], ec[m], ev[m] = min(r + 1, rows - 1), c, 0.5 * a
                    er[m + 1], ec[m + 1], ev[m + 1] = max(r - 1, 0), c, -0.5 * a
                    m += 2
                if cols > 1:
                    er[m], ec[m], ev[m] = r, min(c + 1, cols - 1), 0.5 * b
                    er[m + 1], ec[m + 1], ev[m + 1] = r, max(c - 1, 0), -0.5 * b
                    m += 2
                for p in range(m):
                    ip = er[p] * cols + ec[p]
                    if pass_ == 0:
                        rhs[ip] += wt * ev[p] * resid[j]
                    for q in range(m):
                        k = slot[er[q] - er[p] + 2, ec[q] - ec[p] + 2]
                        vals[ip, k] += wt * ev[p] * ev[q]
    centre = slot[2, 2]
    for i in range(n):
        vals[i, centre] += diag[i]
    # compress to CSR, columns sorted
    indptr = np.zeros(n + 1, np.int32)
    for i in range(n):
        cnt = 0
        for k in range(sdr.shape[0]):
            if vals[i, k] != 0.0:
                cnt += 1
        indptr[i + 1] = indptr[i] + cnt
    indices = np.empty(indptr[n], np.int32)
    data = np.empty(indptr[n])
    for i in range(n):
        r, c = i // cols, i % cols
        pos = indptr[i]
        for k in range(sdr.shape[0]):
            if vals[i, k] != 0.0:
                col = (r + sdr[k]) * cols + (c + sdc[k])
                q = pos
                while q > indptr[i] and indices[q - 1] > col:  # insertion sort
                    indices[q] = indices[q - 1]
                    data[q] = data[q - 1]
                    q -= 1
                indices[q] = col
                data[q] = vals[i, k]
                pos += 1
    return indptr, indices, data, rhs


def normal_equations(shape, u, across_weight, w, diag, resid):
    """The photoclinometry normal equations as a scipy.sparse CSR matrix and right-hand side.

    Parameters
    ----------
    shape : tuple of int
        (rows, cols).
    u : array_like, shape (2,)
        Unit direction of the light's slope (row, col); ``t`` is across it.
    across_weight : float
        ``lam_t``.
    w : ndarray, shape (rows * cols,)
        Weight of each cell's slope equation (0: shadowed or saturated).
    diag : ndarray, shape (rows * cols,)
        Ridge plus anchor weight of each cell.
    resid : ndarray, shape (rows * cols,)
        The slope along ``u`` the image adds (per cell).

    Returns
    -------
    a_mat : scipy.sparse.csr_matrix, shape (n, n)
        ``D_u^T W D_u + lam_t D_t^T D_t + diag(diag)`` (at most 13 entries a row, 9 inside).
    rhs : ndarray, shape (n,)
        ``D_u^T W resid``.
    """
    rows, cols = (int(x) for x in shape)
    u = np.asarray(u, dtype=np.float64)
    w = np.ascontiguousarray(w, dtype=np.float64)
    indptr, indices, data, rhs = _assemble(
        rows, cols, u[0], u[1], -u[1], u[0], float(across_weight), w,
        np.ascontiguousarray(diag, dtype=np.float64), np.ascontiguousarray(resid, np.float64),
        _SLOT, _SLOT_DR, _SLOT_DC,
    )  # fmt: skip
    n = rows * cols
    a_mat = sparse.csr_matrix((data, indices, indptr), shape=(n, n))
    a_mat.has_sorted_indices = True
    return a_mat, rhs


def _preconditioner(shape, u, lam_t, shift):
    """M^-1 of the operator's mirror-averaged cosine-diagonal part (symmetric, positive)."""
    rows, cols = shape
    t = np.array([-u[1], u[0]])
    q_rr = u[0] ** 2 + lam_t * t[0] ** 2
    q_cc = u[1] ** 2 + lam_t * t[1] ** 2
    q_rc = u[0] * u[1] + lam_t * t[0] * t[1]
    sr = np.sin(np.pi * np.arange(rows) / rows)[:, None]
    sc = np.sin(np.pi * np.arange(cols) / cols)[None, :]
    base = q_rr * sr * sr + q_cc * sc * sc + shift
    cross = 2.0 * q_rc * sr * sc
    inv = 0.5 * (1.0 / (base + cross) + 1.0 / (base - cross))

    inv = inv.astype(np.float32)

    def apply(x):  # single precision: a preconditioner only has to be close
        f = sfft.dctn(
            x.reshape(shape).astype(np.float32), type=2, norm="ortho", workers=min(2, fft_workers())
        )
        f *= inv
        return (
            sfft.idctn(f, type=2, norm="ortho", workers=min(2, fft_workers()))
            .ravel()
            .astype(np.float64)
        )

    n = rows * cols
    return splinalg.LinearOperator((n, n), matvec=apply, dtype=np.float64)


def photoclinometry(
    points_rc, values, shape, *, guide: Guide, options: PhotoclinometryOptions | None = None
):
    """Linearised photoclinometry anchored on the samples (see the module docstring).

    Parameters
    ----------
    points_rc : array_like, shape (k, 2)
        Measured cells (row, col).
    values : array_like, shape (k,)
        Measured heights or depths (m).
    shape : tuple of int
        Output grid (rows, cols), the guide's.
    guide : Guide
        The sun frame (and optionally the co-located frame, for the albedo ratio).
    options : PhotoclinometryOptions, optional

    Returns
    -------
    Reconstructed
        ``heights`` (rows, cols) and ``info``: ``shading_share``, ``heldout_share``,
        ``gamma``, ``frames``, ``azimuth_deg``, ``gain``, ``cg_iterations``, ``cg_converged``.
    """
    o = options or PhotoclinometryOptions()
    if guide is None:
        raise ValueError("photoclinometry needs the guide image (guide=Guide(...))")
    so = o.shading()
    lin = linear_field(points_rc, values, shape)
    if guide.shape != lin.shape:
        raise ValueError(f"guide image has shape {guide.shape}, the output grid {lin.shape}")
    # shadowed pixels (read from the frames alone: shading.shadow_masks) leave the
    # calibration and the slope equations
    name, image, valid = shading_frames(guide, so, linear=lin)[0]
    cal = calibrate(image, None, None, spacing=guide.spacing, valid=valid, linear=lin,
                    options=so.calibration())  # fmt: skip
    gamma = fallback_gamma(cal.usable_share, so) if cal.gain > 0 else 0.0
    frames = "+".join([name, *(guide.flat_frames if guide.flat is not None and o.use_flat else ())])
    info = {
        "shading_share": float(cal.share),
        "heldout_share": float(cal.heldout_share),
        "gamma": gamma,
        "frames": frames,
        "azimuth_deg": float(cal.azimuth_deg),
        "gain": cal.gain,
        "cg_iterations": 0,
        "cg_converged": True,
        "valid_share": float(valid.mean()),
    }
    if gamma == 0.0:
        return Reconstructed(lin.heights, info)
    smooth = ndimage.gaussian_filter(image, o.image_sigma, truncate=3.0) if o.image_sigma else image
    p_s = np.clip((smooth - cal.a) / (o.gain * cal.gain), -o.clip, o.clip) * guide.spacing
    d, iterations, status = _correction(lin, p_s, valid, cal.direction, o)
    info["cg_iterations"] = iterations
    info["cg_converged"] = status == 0

    # the correction is anchored on the samples: remade from the kept ones only
    def remade(keep):
        return _correction(keep, p_s, valid, cal.direction, o)[0]

    checked = remade if o.heldout_check else None
    z = checked_blend(lin, d, gamma, info, remade=checked, pool_folds=True, clip=o.detail_clip)
    return Reconstructed(z, info)


def _correction(lin, p_s, valid, u, o: PhotoclinometryOptions) -> tuple[np.ndarray, int, int]:
    """The correction ``d`` (rows, cols) to the linear reconstruction ``lin`` whose slope along
    ``u`` matches the image's ``p_s`` (value units per cell) on ``valid`` cells, anchored on
    ``lin``'s samples; with the CG iterations and status."""
    rows, cols = lin.shape
    n = rows * cols
    lr, lc = central_gradient(lin.heights)
    resid = np.where(valid, p_s - (u[0] * lr + u[1] * lc), 0.0).ravel()
    w_img = valid.ravel().astype(np.float64)
    lam_r = o.ridge / lin.pitch**2
    diag = np.full(n, lam_r)
    cells = np.rint(lin.points).astype(np.int64)
    inside = (cells[:, 0] >= 0) & (cells[:, 0] < rows) & (cells[:, 1] >= 0) & (cells[:, 1] < cols)
    diag[cells[inside, 0] * cols + cells[inside, 1]] += o.anchor_weight
    lam_t = o.across_weight
    a_mat, rhs = normal_equations(lin.shape, u, lam_t, w_img, diag, resid)
    shift = lam_r + o.anchor_weight * inside.sum() / n
    m_inv = _preconditioner(lin.shape, u, lam_t, shift)
    iterations = [0]

    def count(_):
        iterations[0] += 1

    d, status = splinalg.cg(a_mat, rhs, rtol=o.rtol, maxiter=o.max_iter, M=m_inv, callback=count)
    return d.reshape(lin.shape), iterations[0], status
