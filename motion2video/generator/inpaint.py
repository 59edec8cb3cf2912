"""A hole filled with patches of the picture itself: multi-scale patch-based inpainting.

The hole is completed coarse to fine (Wexler, Shechtman and Irani, "Space-time completion of video", 2007): at each
level of an image pyramid, every patch that overlaps the hole is matched to its nearest patch lying wholly outside it
(PatchMatch's propagation and random search, Barnes et al. 2009), then each hole pixel becomes the mean of what the
matched patches put there, weighted by how well each matched; matching and voting alternate a few times. The
coarsest level starts from OpenCV's Navier-Stokes inpainting; each finer level starts from the coarser matches. At
the end each hole pixel is the centre pixel of its own patch's match, which keeps the picture's grain, and where the
fill's slow shading and the diffusion's agree within a few levels the diffusion's is taken (:func:`diffused_shading`).

Why this and not only OpenCV: its classical inpaintings (Navier-Stokes, Telea) diffuse the colours of the hole's
border inward, which is right for a flat wall but draws the dark things that touch a large hole (a ski binding at a
boot, the shadow under an arm) into a grey smear shaped like the person, and fills asphalt, snow or foliage with a
smooth blur; the patch-based inpaintings of ``cv2.xphoto`` (frequency-selective reconstruction, shift-map), a little
slower than these patches at 256 px, left dark streaks or copied whole regions over the hole (docs/results.md, "The
background behind the person"; docs/experiments.md). No well-kept Python library offers PatchMatch completion; the few
packages that wrap one build C++ at install.

Patches are compared in a reduced space: the first :attr:`PatchSettings.dims` principal components of the known
patches of each level (7 x 7 x 3 = 147 numbers down to 16), which keeps every comparison a short vector difference.

Images are (H, W, 3) float or uint8 RGB, masks (H, W) bool; pixels x right, y down.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# OpenCV's Navier-Stokes inpainting: the neighbourhood radius (pixels) of each filled pixel, for the whole-picture fill
# the patches fall back on and take their slow shading from
DIFFUSION_RADIUS_PX = 5


@dataclass(frozen=True)
class PatchSettings:
    """How :func:`patch_inpaint` works.

    Attributes:
        radius: patch half-size in pixels (7 x 7 patches).
        dims: principal components a patch is compared by.
        coarsest: the pyramid is halved while its shorter side stays at least this many pixels ...
        sources: ... and at least this many patches lie wholly outside the hole.
        iterations: (matching-and-voting rounds, PatchMatch sweeps per round) at the coarsest level, the levels
            between, and the finest.
        sample: known patches the principal components are computed from (a random sample).
        grain: each hole pixel the centre of its own patch's match at the end, not the votes' mean.
        shading_sigma, shading_tolerance: the slow shading taken from a diffusing inpainting where it agrees with the
            patches (:func:`diffused_shading`); a tolerance of 0 keeps the patches' own.
        seed: random generator seed (the result is the same for the same input and seed).
    """

    radius: int = 3
    dims: int = 16
    coarsest: int = 32
    iterations: tuple[tuple[int, int], tuple[int, int], tuple[int, int]] = ((4, 3), (3, 2), (2, 2))
    sources: int = 400
    sample: int = 4000
    grain: bool = True
    shading_sigma: float = 4.0
    shading_tolerance: float = 12.0
    seed: int = 0


def patch_offsets(radius: int) -> tuple[np.ndarray, np.ndarray]:
    """The (dy, dx) of every pixel of a patch around its centre: two (P,) int arrays, P = (2 radius + 1)^2, rows
    first."""
    d = np.arange(-radius, radius + 1)
    dy, dx = np.meshgrid(d, d, indexing="ij")
    return dy.ravel(), dx.ravel()


def patches(image: np.ndarray, ys: np.ndarray, xs: np.ndarray, radius: int) -> np.ndarray:
    """(N, P * 3) float32: the patches of ``image`` (H, W, 3) centred at pixels (``ys``, ``xs``) (N,), the picture's
    edge repeated where a patch reaches past it."""
    h, w = image.shape[:2]
    dy, dx = patch_offsets(radius)
    rows = np.clip(ys[:, None] + dy[None], 0, h - 1)
    cols = np.clip(xs[:, None] + dx[None], 0, w - 1)
    return np.asarray(image, np.float32)[rows, cols].reshape(len(ys), -1)


def patch_features(image: np.ndarray, ys: np.ndarray, xs: np.ndarray, radius: int, mean: np.ndarray,
                   basis: np.ndarray) -> np.ndarray:
    """(N, D) float32: the patches at (``ys``, ``xs``) in the principal components ``basis`` (P * 3, D) around
    ``mean`` (P * 3,), in chunks so that no more than a few MB of patches are held at once."""
    out = np.empty((len(ys), basis.shape[1]), np.float32)
    for start in range(0, len(ys), 8192):
        part = slice(start, start + 8192)
        out[part] = (patches(image, ys[part], xs[part], radius) - mean) @ basis
    return out


def nearest_patches(features: np.ndarray, targets: np.ndarray, sources: np.ndarray, nearest: np.ndarray,
                    shape: tuple[int, int], sweeps: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """PatchMatch: for each target pixel, the source pixel whose patch is nearest.

    Args:
        features: (H * W, D) every pixel's patch features (a target's from the current fill).
        targets: (T,) flat indices of the pixels whose patch overlaps the hole.
        sources: (H * W,) bool, True where a patch lies wholly outside the hole (and inside the picture).
        nearest: (H * W,) int, each pixel's current source (flat index); read for the targets' neighbours.
        shape: (H, W). sweeps: rounds of propagation and random search.
    Returns:
        (nearest updated at the targets, (T,) the squared feature distance to each target's source).
    """
    h, w = shape
    nearest = nearest.copy()
    ty, tx = np.divmod(targets, w)
    own = features[targets]
    match = nearest[targets]
    diff = own - features[match]
    best = np.einsum("nd,nd->n", diff, diff)

    def consider(candidate: np.ndarray, ok: np.ndarray) -> None:
        idx = np.flatnonzero(ok)
        c = candidate[idx]
        diff = own[idx] - features[c]
        d = np.einsum("nd,nd->n", diff, diff)
        better = d < best[idx]
        best[idx[better]] = d[better]
        match[idx[better]] = c[better]

    for _ in range(sweeps):
        # propagation, all pixels at once (jump flooding): a neighbour's source, moved back by the step
        for step in (4, 2, 1):
            for my, mx in ((step, 0), (-step, 0), (0, step), (0, -step)):
                ny, nx = ty + my, tx + mx
                inside = (ny >= 0) & (ny < h) & (nx >= 0) & (nx < w)
                sy, sx = np.divmod(nearest[np.where(inside, ny * w + nx, 0)], w)
                cy, cx = sy - my, sx - mx
                ok = inside & (cy >= 0) & (cy < h) & (cx >= 0) & (cx < w)
                candidate = np.where(ok, cy * w + cx, 0)
                consider(candidate, ok & sources[candidate])
                nearest[targets] = match
        # random search around the current source, in windows halving from half the picture
        radius = max(h, w) // 2
        while radius >= 1:
            sy, sx = np.divmod(match, w)
            cy = sy + rng.integers(-radius, radius + 1, len(match))
            cx = sx + rng.integers(-radius, radius + 1, len(match))
            ok = (cy >= 0) & (cy < h) & (cx >= 0) & (cx < w)
            candidate = np.where(ok, cy * w + cx, 0)
            consider(candidate, ok & sources[candidate])
            radius //= 2
        nearest[targets] = match
    return nearest, best


def vote(image: np.ndarray, hole: np.ndarray, targets: np.ndarray, nearest: np.ndarray, distance: np.ndarray,
         radius: int) -> np.ndarray:
    """(H, W, 3) float32: ``image`` with each hole pixel the weighted mean of the colours the matched patches put
    on it. A target patch at ``targets`` (T,) with source ``nearest[targets]`` and squared feature ``distance``
    (T,) weighs exp(-distance / (2 x its 75th percentile)): a patch that matched well counts more."""
    h, w = hole.shape
    ty, tx = np.divmod(targets, w)
    sy, sx = np.divmod(nearest[targets], w)
    weight = np.exp(-distance / (2 * np.percentile(distance, 75) + 1e-6))
    slot = np.full(h * w, -1)
    slot[np.flatnonzero(hole)] = np.arange(int(hole.sum()))  # hole pixel -> its row in the sums
    sums = np.zeros((int(hole.sum()), 4))
    dy, dx = patch_offsets(radius)
    for oy, ox in zip(dy, dx):
        qy, qx = ty + oy, tx + ox
        ok = (qy >= 0) & (qy < h) & (qx >= 0) & (qx < w)
        q = slot[np.where(ok, qy * w + qx, 0)]
        ok &= q >= 0
        colours = image[sy[ok] + oy, sx[ok] + ox]
        for c in range(3):
            sums[:, c] += np.bincount(q[ok], weights=colours[:, c] * weight[ok], minlength=len(sums))
        sums[:, 3] += np.bincount(q[ok], weights=weight[ok], minlength=len(sums))
    out = np.array(image, np.float32)
    voted = sums[:, 3] > 0
    filled = out.reshape(-1, 3)
    rows = np.flatnonzero(hole)[voted]
    filled[rows] = (sums[voted, :3] / sums[voted, 3:]).astype(np.float32)
    return out


def patch_inpaint(image: np.ndarray, hole: np.ndarray, *, settings: PatchSettings = PatchSettings()) -> np.ndarray:
    """``image`` with ``hole`` filled from its own patches (see the module's docstring).

    Args:
        image: (H, W, 3) uint8 RGB. hole: (H, W) bool, the pixels to fill.
    Returns:
        (H, W, 3) uint8, equal to ``image`` outside the hole. Where no patch of the picture lies wholly outside the
        hole (a hole over nearly all of it), OpenCV's Navier-Stokes inpainting alone.
    """
    import cv2

    hole = np.asarray(hole, bool)
    image = np.ascontiguousarray(image, np.uint8)
    r = settings.radius
    kernel = np.ones((2 * r + 1, 2 * r + 1), np.uint8)
    levels = [(image.astype(np.float32), hole)]
    while min(levels[-1][1].shape) // 2 >= settings.coarsest:
        small = cv2.pyrDown(levels[-1][0])
        size = (small.shape[1], small.shape[0])
        small_hole = cv2.resize(levels[-1][1].astype(np.float32), size, interpolation=cv2.INTER_AREA) > 0
        if (cv2.dilate(small_hole.astype(np.uint8), kernel) == 0).sum() < settings.sources:
            break  # too few whole patches outside the hole at this size to fill it from
        levels.append((small, small_hole))
    rng = np.random.default_rng(settings.seed)
    coarser = None
    for depth in range(len(levels) - 1, -1, -1):
        picture, level_hole = levels[depth]
        h, w = level_hole.shape
        reach = cv2.dilate(level_hole.astype(np.uint8), kernel) > 0  # centres whose patch overlaps the hole
        sources = ~reach
        sources[:r], sources[-r:], sources[:, :r], sources[:, -r:] = False, False, False, False
        known = np.flatnonzero(sources)
        if len(known) == 0:
            return cv2.inpaint(image, hole.astype(np.uint8), DIFFUSION_RADIUS_PX, cv2.INPAINT_NS)
        targets = np.flatnonzero(reach)
        nearest = start_matches(coarser, (h, w), targets, known, sources.ravel(), rng)
        if depth == len(levels) - 1:
            start = np.clip(np.rint(picture), 0, 255).astype(np.uint8)
            fill = cv2.inpaint(start, level_hole.astype(np.uint8), r, cv2.INPAINT_NS).astype(np.float32)
            rounds, sweeps = settings.iterations[0]
        else:
            fill = vote(picture, level_hole, targets, nearest, np.ones(len(targets)), r)
            rounds, sweeps = settings.iterations[1 if depth > 0 else 2]
        fill = np.where(level_hole[..., None], fill, picture)
        ys, xs = np.divmod(np.arange(h * w), w)
        sample = rng.choice(known, min(len(known), settings.sample), replace=False)
        known_patches = patches(picture, *np.divmod(sample, w), r)
        mean = known_patches.mean(0)
        basis = np.linalg.svd(known_patches - mean, full_matrices=False)[2][:settings.dims].T.astype(np.float32)
        features = patch_features(fill, ys, xs, r, mean, basis)  # the sources' never change at this level
        for _ in range(rounds):
            features[targets] = patch_features(fill, *np.divmod(targets, w), r, mean, basis)
            nearest, distance = nearest_patches(features, targets, sources.ravel(), nearest, (h, w), sweeps, rng)
            fill = vote(fill, level_hole, targets, nearest, distance, r)
        coarser = (nearest, (h, w))
    # the finest level's last matches, each hole pixel the centre of its own patch's match: the mean the votes take
    # smooths the grain of asphalt or snow away, and a smooth patch in a grainy picture shows where the person was
    if settings.grain:
        inside = np.flatnonzero(hole)
        fill.reshape(-1, 3)[inside] = picture.reshape(-1, 3)[nearest[inside]]
    if settings.shading_tolerance > 0:
        diffused = cv2.inpaint(image, hole.astype(np.uint8), DIFFUSION_RADIUS_PX, cv2.INPAINT_NS)
        fill = diffused_shading(fill, diffused, settings)  # fill is the picture itself outside the hole
    return np.where(hole[..., None], np.clip(np.rint(fill), 0, 255), image).astype(np.uint8)


def diffused_shading(fill: np.ndarray, diffused: np.ndarray, settings: PatchSettings) -> np.ndarray:
    """(H, W, 3) float32: ``fill`` with its slow shading replaced by ``diffused``'s where the two agree.

    Patches copied from elsewhere bring that place's shade: on a backdrop lit in a gradient, the hole came out a few
    levels lighter or darker than around it. Where the blurred fill and the blurred diffusion (a Gaussian of
    :attr:`PatchSettings.shading_sigma` pixels at 256) differ by a few levels, the diffusion's shading is taken and
    the patches keep only their grain; where they differ by much more (the diffusion drew a binding or a shadow into
    the hole), the patches are kept. The weight is exp(-(difference / tolerance)^2), the difference the colour
    distance of the blurred pictures.

    Args:
        fill: (H, W, 3) the patch fill, the picture itself outside the hole. diffused: (H, W, 3) the same hole filled by
            OpenCV's Navier-Stokes inpainting.
    """
    import cv2

    sigma = settings.shading_sigma * max(fill.shape[:2]) / 256
    fill = np.asarray(fill, np.float32)
    blurred = cv2.GaussianBlur(np.asarray(diffused, np.float32), (0, 0), sigma)
    difference = blurred - cv2.GaussianBlur(fill, (0, 0), sigma)
    distance = np.linalg.norm(difference, axis=-1, keepdims=True)
    return fill + np.exp(-(distance / settings.shading_tolerance) ** 2) * difference


def start_matches(coarser: tuple[np.ndarray, tuple[int, int]] | None, shape: tuple[int, int], targets: np.ndarray,
                  known: np.ndarray, sources: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(H * W,) int: each pixel's first source at a level of ``shape`` (H, W).

    Every pixel is its own source, and each target (flat indices ``targets``) takes the coarser level's source of
    its parent pixel, doubled (``coarser``: that level's (h * w,) sources and its (h, w); None at the coarsest
    level), or a random known pixel (``known`` flat indices) where there is none or it is not a source
    (``sources`` (H * W,) bool).
    """
    h, w = shape
    nearest = np.arange(h * w)
    guess = known[rng.integers(0, len(known), len(targets))]
    if coarser is not None:
        parent, (ch, cw) = coarser
        ty, tx = np.divmod(targets, w)
        sy, sx = np.divmod(parent[np.minimum(ty // 2, ch - 1) * cw + np.minimum(tx // 2, cw - 1)], cw)
        sy, sx = np.clip(2 * sy + ty % 2, 0, h - 1), np.clip(2 * sx + tx % 2, 0, w - 1)
        upscaled = sy * w + sx
        guess = np.where(sources[upscaled], upscaled, guess)
    nearest[targets] = guess
    return nearest
