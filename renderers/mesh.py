"""Offscreen triangle-mesh rendering with pyrender: one GL renderer per process, a lit scene, a shared camera.

Backend: ``platform="osmesa"`` (software, CPU; Debian's ``libosmesa6``) or ``"egl"`` (GPU, or Mesa on
CPU). PyOpenGL fixes its platform when ``OpenGL`` is first imported, so this module sets
``PYOPENGL_PLATFORM`` and imports pyrender lazily, on the first render; asking for another platform
later in the same process raises :class:`RenderError`.

GL renderers are expensive to create and delete (first render 50-200 ms, delete 60-80 ms), so
:func:`get_offscreen_renderer` keeps one ``pyrender.OffscreenRenderer`` per (width, height, platform) for
the whole process and every :class:`MeshRenderer` reuses it. :func:`release_renderers` frees them.

Colours: vertex colours are sRGB in [0, 1]; they are linearised before shading because pyrender's
shader gamma-encodes its output. OSMesa has no multisampling, so edges are aliased.
"""

from __future__ import annotations

import os
import sys
import threading
from dataclasses import dataclass

import numpy as np

from motion2video.core.camera import PinholeCamera, project
from motion2video.core.errors import InputError

PLATFORMS = ("osmesa", "egl")
_PLATFORM_CLASSES = {"osmesa": "OSMesaPlatform", "egl": "EGLPlatform"}
_RENDERERS: dict[tuple[int, int, str], object] = {}
_LOCK = threading.RLock()


# The GL library each backend loads, and the Debian package that installs it.
GL_LIBRARIES = {"osmesa": ("OSMesa", "libosmesa6"), "egl": ("EGL", "libegl1")}


class GLUnavailable(InputError):
    """The GL library of a backend is not installed: a one-line, fixable problem (exit 2 from the CLI)."""


def gl_library(platform: str) -> str | None:
    """The path (or soname) of ``platform``'s GL library when the dynamic loader can load it, else None.
    Mirrors how PyOpenGL looks for it (``libNAME.so``, then ``libNAME.so.N``)."""
    import ctypes
    import ctypes.util

    name = GL_LIBRARIES[platform][0]
    candidates = [ctypes.util.find_library(name), f"lib{name}.so"] + [f"lib{name}.so.{i}" for i in range(9, -1, -1)]
    for candidate in candidates:
        if not candidate:
            continue
        try:
            ctypes.CDLL(candidate)
        except OSError:
            continue
        return candidate
    return None


def gl_unavailable_message(platform: str) -> str:
    """What to do when ``platform``'s GL library is missing (one line)."""
    name, package = GL_LIBRARIES[platform]
    return (f"the mesh and face styles need the {name} library (lib{name}) for {platform} rendering, and it is "
            f"not installed: install it with `sudo apt-get install {package}` (Debian/Ubuntu; `make setup` does "
            f"this), or use --style skeleton or --style heatmap, which need no GL")


class RenderError(RuntimeError):
    """A render failed: the GL backend is unusable or returned nothing where geometry is in view."""


@dataclass(frozen=True)
class Lighting:
    """A key light, a fill light and a rim light fixed to the camera, plus ambient light.

    Directions are given in camera axes (x right, y up, z towards the viewer); each light shines along
    the negative of its vector, i.e. the vector points from the scene to the light.

    Attributes:
        key: direction to the key light (upper left, in front).
        fill: direction to the fill light (right, slightly below).
        rim: direction to the rim light (above, behind).
        key_intensity, fill_intensity, rim_intensity: directional light intensities.
        ambient: ambient light level (grey).
    """

    key: tuple[float, float, float] = (-0.5, 0.6, 1.0)
    fill: tuple[float, float, float] = (0.8, -0.1, 0.8)
    rim: tuple[float, float, float] = (0.0, 0.8, -0.6)
    key_intensity: float = 2.6
    fill_intensity: float = 1.0
    rim_intensity: float = 0.8
    ambient: float = 0.35


@dataclass(frozen=True)
class MeshFrame:
    """One rendered frame.

    Attributes:
        color: (H, W, 3) uint8 RGB image (the background composited where there is no geometry).
        mask: (H, W) bool silhouette, True where geometry covers the pixel.
        depth: (H, W) float32 distance along the viewing axis in metres, 0 where there is no geometry.
    """

    color: np.ndarray
    mask: np.ndarray
    depth: np.ndarray


# --- pure helpers ------------------------------------------------------------------------------------


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals.

    Args:
        vertices: (V, 3) float positions.
        faces: (F, 3) int triangle indices, counter-clockwise seen from outside.
    Returns:
        (V, 3) float32 unit normals (a vertex in no face gets +z).
    """
    v = np.asarray(vertices, dtype=np.float32)
    f = np.asarray(faces, dtype=np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]  # (F, 3) each
    e1, e2 = b - a, c - a
    face_n = np.empty_like(e1)  # (F, 3) cross product, length = 2 * area (written out: np.cross is slow)
    face_n[:, 0] = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
    face_n[:, 1] = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
    face_n[:, 2] = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    corners = f.T.ravel()  # (3F,) every face's first corners, then second, then third
    normals = np.stack([np.bincount(corners, weights=np.tile(face_n[:, k], 3), minlength=len(v))
                        for k in range(3)], axis=1)  # (V, 3)
    length = np.linalg.norm(normals, axis=1, keepdims=True)  # (V, 1)
    normals = np.where(length > 1e-12, normals / np.maximum(length, 1e-12), np.array([0.0, 0.0, 1.0]))
    return normals.astype(np.float32)


def srgb_to_linear(colors: np.ndarray) -> np.ndarray:
    """sRGB values in [0, 1] -> linear light (the standard piecewise curve), same shape."""
    c = np.clip(np.asarray(colors, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def as_unit_colors(colors: np.ndarray | tuple, count: int | None = None) -> np.ndarray:
    """Colours as float64 in [0, 1]: integer arrays (uint8, or a tuple of ints) are 0-255 and divided by
    255; floats must already lie in [0, 1]. A single (3,) colour is broadcast to ``count`` rows when
    ``count`` is given."""
    arr = np.asarray(colors)
    if arr.dtype.kind in "iub":
        arr = arr.astype(np.float64) / 255.0
    arr = arr.astype(np.float64)
    if arr.size and (arr.min() < 0.0 or arr.max() > 1.0):
        raise ValueError("float colours must lie in [0, 1] (give integers for 0-255)")
    if count is not None and arr.ndim == 1:
        arr = np.broadcast_to(arr, (count, arr.shape[0]))
    return arr


def _camera_light_pose(camera_pose: np.ndarray, direction_cam: tuple[float, float, float]) -> np.ndarray:
    """(4, 4) pose of a directional light whose -z axis shines along -direction (camera axes)."""
    z = np.asarray(direction_cam, dtype=np.float64)
    z = z / np.linalg.norm(z)
    helper = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    local = np.eye(4)
    local[:3, 0], local[:3, 1], local[:3, 2] = x, y, z
    return camera_pose @ local


# --- the GL renderer cache ---------------------------------------------------------------------------


def _import_pyrender(platform: str):
    """Import pyrender for ``platform``, setting PYOPENGL_PLATFORM first; raise RenderError when OpenGL
    was already set up for another platform in this process."""
    if platform not in PLATFORMS:
        raise ValueError(f"platform must be one of {PLATFORMS}, got {platform!r}")
    if "OpenGL.platform" in sys.modules:
        import OpenGL.platform

        active = type(OpenGL.platform.PLATFORM).__name__
        if active != _PLATFORM_CLASSES[platform]:
            raise RenderError(
                f"OpenGL was already initialised with {active} in this process; cannot render with "
                f"platform={platform!r} (set PYOPENGL_PLATFORM={platform} before anything imports OpenGL)"
            )
    if "pyrender" not in sys.modules and gl_library(platform) is None:
        raise GLUnavailable(gl_unavailable_message(platform))  # PyOpenGL would fail with an AttributeError
    os.environ["PYOPENGL_PLATFORM"] = platform
    try:
        import pyrender
    except ImportError as err:  # pragma: no cover - depends on the machine
        raise RenderError(f"cannot import pyrender for platform {platform!r}: {err}") from err
    return pyrender


class _ProgramCache:
    """Shader programs of one GL renderer, keyed by shader files and defines.

    Replaces pyrender's ``ShaderProgramCache``, whose key includes ``OpenGL.contextdata.getContext()``:
    under OSMesa that returns a new ctypes pointer object on every call, so each frame compiled a new
    shader program (~4 ms) and leaked the old one. A cache belongs to one renderer, hence one context,
    so the context is not needed in the key.
    """

    def __init__(self, shader_dir: str):
        self.shader_dir = shader_dir
        self._programs: dict[tuple, object] = {}

    def get_program(self, vertex_shader, fragment_shader, geometry_shader=None, defines=None):
        from pyrender.shader_program import ShaderProgram

        defines = dict(defines or {})
        key = (vertex_shader, fragment_shader, geometry_shader, tuple(sorted(defines.items())))
        program = self._programs.get(key)
        if program is None:
            paths = [None if name is None else os.path.join(self.shader_dir, name)
                     for name in (vertex_shader, fragment_shader, geometry_shader)]
            program = ShaderProgram(vertex_shader=paths[0], fragment_shader=paths[1],
                                    geometry_shader=paths[2], defines=defines)
            self._programs[key] = program
        return program

    def __len__(self) -> int:
        return len(self._programs)

    def clear(self) -> None:
        for program in self._programs.values():
            program.delete()
        self._programs = {}


def get_offscreen_renderer(width: int, height: int, *, platform: str = "osmesa"):
    """The process-wide ``pyrender.OffscreenRenderer`` for this size and platform (created on first use)."""
    key = (int(width), int(height), str(platform))
    with _LOCK:
        renderer = _RENDERERS.get(key)
        if renderer is None:
            pyrender = _import_pyrender(platform)
            try:
                renderer = pyrender.OffscreenRenderer(key[0], key[1])
            except Exception as err:  # GL context creation failed: say which backend and why
                raise RenderError(f"could not create a {platform} offscreen renderer {key[0]}x{key[1]}: "
                                  f"{type(err).__name__}: {err}") from err
            inner = renderer._renderer  # pyrender.Renderer: swap in the context-free program cache
            inner._program_cache = _ProgramCache(inner._program_cache.shader_dir)
            _RENDERERS[key] = renderer
    return renderer


def release_renderers() -> None:
    """Delete every cached GL renderer (they are recreated on demand)."""
    with _LOCK:
        for renderer in _RENDERERS.values():
            renderer.delete()
        _RENDERERS.clear()


# --- the mesh renderer -------------------------------------------------------------------------------


class MeshRenderer:
    """Renders triangle meshes with vertex colours through a shared offscreen GL renderer.

    Args:
        width, height: image size in pixels.
        platform: ``"osmesa"`` (CPU) or ``"egl"``.
        lighting: the light rig.
    """

    def __init__(self, width: int, height: int, *, platform: str = "osmesa", lighting: Lighting = Lighting()):
        if width <= 0 or height <= 0:
            raise ValueError(f"image size must be positive, got {width}x{height}")
        if platform not in PLATFORMS:
            raise ValueError(f"platform must be one of {PLATFORMS}, got {platform!r}")
        self.width, self.height, self.platform, self.lighting = int(width), int(height), platform, lighting
        self._scene = None
        self._camera_node = None
        self._light_nodes: list = []
        self._camera_key: tuple | None = None
        self._material = None

    @property
    def offscreen(self):
        """The shared ``pyrender.OffscreenRenderer`` this renderer draws with."""
        return get_offscreen_renderer(self.width, self.height, platform=self.platform)

    def _setup(self, pyrender) -> None:
        if self._scene is not None:
            return
        a = self.lighting.ambient
        self._scene = pyrender.Scene(bg_color=(0.0, 0.0, 0.0, 1.0), ambient_light=(a, a, a))
        self._material = pyrender.MetallicRoughnessMaterial(
            baseColorFactor=(1.0, 1.0, 1.0, 1.0), metallicFactor=0.0, roughnessFactor=0.75, doubleSided=True)

    def _set_camera(self, pyrender, camera: PinholeCamera) -> None:
        key = (camera.position, camera.target, camera.yfov, camera.width, camera.height)
        if key == self._camera_key:
            return
        scene = self._scene
        if self._camera_node is not None:
            scene.remove_node(self._camera_node)
            for node in self._light_nodes:
                scene.remove_node(node)
        distance = float(np.linalg.norm(np.subtract(camera.target, camera.position)))
        gl_cam = pyrender.IntrinsicsCamera(
            fx=camera.focal, fy=camera.focal, cx=0.5 * camera.width, cy=0.5 * camera.height,
            znear=max(0.01, 0.02 * distance), zfar=100.0 * max(distance, 1.0))
        pose = camera.gl_pose()
        self._camera_node = scene.add(gl_cam, pose=pose)
        lt = self.lighting
        self._light_nodes = [
            scene.add(pyrender.DirectionalLight(color=np.ones(3), intensity=intensity),
                      pose=_camera_light_pose(pose, direction))
            for direction, intensity in ((lt.key, lt.key_intensity), (lt.fill, lt.fill_intensity),
                                         (lt.rim, lt.rim_intensity))
            if intensity > 0
        ]
        self._camera_key = key

    def render_mesh(
        self,
        vertices: np.ndarray,
        faces: np.ndarray,
        *,
        vertex_colors: np.ndarray | tuple,
        camera: PinholeCamera,
        background: np.ndarray | tuple = (255, 255, 255),
        normals: np.ndarray | None = None,
    ) -> MeshFrame:
        """Render one mesh.

        Args:
            vertices: (V, 3) world positions, metres.
            faces: (F, 3) int triangle indices.
            vertex_colors: (V, 3) sRGB colours (float in [0, 1] or uint8) or one (3,) colour.
            camera: the camera; its size must equal the renderer's.
            background: an RGB colour (0-255 ints or floats in [0, 1]) or an (H, W, 3) uint8 image.
            normals: (V, 3) vertex normals; computed from the faces when None.
        Returns:
            The frame (colour, silhouette mask, depth).
        Raises:
            RenderError: the GL render failed, or it came back empty while some geometry is in view.
        """
        vertices = np.asarray(vertices, dtype=np.float32)
        faces = np.asarray(faces)
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise ValueError(f"vertices must be (V, 3), got {vertices.shape}")
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise ValueError(f"faces must be a non-empty (F, 3) array, got {faces.shape}")
        if (camera.width, camera.height) != (self.width, self.height):
            raise ValueError(f"camera is {camera.width}x{camera.height} but the renderer is "
                             f"{self.width}x{self.height}")
        if not np.all(np.isfinite(vertices)):
            raise ValueError("vertices contain NaN or Inf")
        colors = as_unit_colors(vertex_colors, count=len(vertices))
        if colors.shape != (len(vertices), 3):
            raise ValueError(f"vertex_colors must be (V, 3) or (3,), got {np.asarray(vertex_colors).shape}")
        bg = self._background(background)
        if normals is None:
            normals = vertex_normals(vertices, faces)

        pyrender = _import_pyrender(self.platform)
        offscreen = self.offscreen
        with _LOCK:
            self._setup(pyrender)
            self._set_camera(pyrender, camera)
            rgba = np.ones((len(vertices), 4), dtype=np.float32)
            rgba[:, :3] = srgb_to_linear(colors)
            primitive = pyrender.Primitive(
                positions=vertices, normals=np.asarray(normals, dtype=np.float32),
                color_0=rgba, indices=faces.astype(np.uint32), material=self._material)
            node = self._scene.add(pyrender.Mesh(primitives=[primitive]))
            try:
                color, depth = offscreen.render(self._scene)
            except Exception as err:
                raise RenderError(f"{self.platform} render failed: {type(err).__name__}: {err}") from err
            finally:
                self._scene.remove_node(node)
        color = np.asarray(color)
        depth = np.asarray(depth, dtype=np.float32)
        if color.shape[:2] != (self.height, self.width) or depth.shape != (self.height, self.width):
            raise RenderError(f"render returned {color.shape} / {depth.shape}, expected "
                              f"{self.height}x{self.width}")
        mask = depth > 0
        if not mask.any() and _any_in_view(vertices, camera):
            raise RenderError("render came back empty although the mesh is in front of the camera")
        out = np.where(mask[..., None], color[..., :3], bg)
        return MeshFrame(color=np.ascontiguousarray(out, dtype=np.uint8), mask=mask, depth=depth)

    def _background(self, background: np.ndarray | tuple) -> np.ndarray:
        bg = np.asarray(background)
        if bg.ndim == 3:
            if bg.shape != (self.height, self.width, 3):
                raise ValueError(f"background image must be ({self.height}, {self.width}, 3), got {bg.shape}")
            return bg.astype(np.uint8)
        if bg.shape != (3,):
            raise ValueError(f"background must be an RGB colour or an image, got shape {bg.shape}")
        rgb = np.round(as_unit_colors(bg) * 255).astype(np.uint8)
        return np.broadcast_to(rgb, (self.height, self.width, 3))

    def close(self) -> None:
        """Drop this renderer's scene; the shared GL renderer stays alive for the process."""
        self._scene = None
        self._camera_node = None
        self._light_nodes = []
        self._camera_key = None


def _any_in_view(vertices: np.ndarray, camera: PinholeCamera) -> bool:
    """Whether some vertex projects inside the image in front of the camera."""
    uvd = project(vertices, camera)  # (V, 3)
    inside = ((uvd[:, 2] > 0.05) & (uvd[:, 0] >= 0) & (uvd[:, 0] < camera.width)
              & (uvd[:, 1] >= 0) & (uvd[:, 1] < camera.height))
    return bool(inside.any())


# A vertex is the front surface when its depth is within this of the depth map's at its pixel (metres; the
# thinnest body parts, wrists and fingers, are a few centimetres thick).
VISIBILITY_TOLERANCE_M = 0.025


# Where two surfaces of the body meet in the picture (a forearm held against the waist, a hand beside a thigh), both
# lie within VISIBILITY_TOLERANCE_M of the depth map and their vertices interleave pixel by pixel: a flow built from
# the nearest shown vertex then alternates between them (the dotted grid of skin and shirt at the waist of a turned
# body in `make demo`). :func:`behind_a_touching_surface` keeps the front one: per shown vertex, its depth behind the
# depth map averaged over the shown vertices of its own surface within TOUCH_SMOOTH_PX pixels; of two shown vertices
# within TOUCH_PX pixels of each other and more than TOUCH_APART_M apart on the body at rest, the one whose average is
# more than TOUCH_MARGIN_M deeper is hidden.
TOUCH_SMOOTH_PX = 3.0
TOUCH_PX = 1.5
TOUCH_APART_M = 0.10
TOUCH_MARGIN_M = 0.003


def behind_a_touching_surface(uv: np.ndarray, seen: np.ndarray, behind: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Shown vertices that lie behind another surface of the body meeting them in the picture.

    Two shown vertices within TOUCH_PX pixels of each other and more than TOUCH_APART_M apart on the body at rest
    belong to two surfaces that meet there. A single vertex's depth behind the depth map is noise at the scale of the
    tolerance (the map is interpolated across triangles, steep near an outline), so each such vertex is judged by
    the average over the shown vertices of its own surface within TOUCH_SMOOTH_PX pixels (those within TOUCH_APART_M
    of it at rest); of a meeting pair, the one whose average is more than TOUCH_MARGIN_M deeper is hidden.

    Args:
        uv: (V, 2) vertex pixels; seen: (V,) bool shown by the depth test; behind: (V,) metres each vertex lies
            behind the depth map at its pixel; rest: (V, 3) the same vertices on the body at rest (metres).
    Returns:
        (V,) bool, a subset of ``seen``.
    """
    from scipy.spatial import cKDTree

    out = np.zeros(len(uv), bool)
    shown = np.flatnonzero(seen)
    if len(shown) < 2:
        return out
    points = np.asarray(uv, np.float64)[shown]
    at_rest = np.ascontiguousarray(np.asarray(rest, np.float32)[shown].T)  # (3, S)
    meet = meeting_pairs(points, at_rest)
    if len(meet) == 0:
        return out
    depth = np.asarray(behind, np.float64)[shown]
    judged = np.unique(meet)  # the vertices where two surfaces meet
    # each judged vertex with every shown vertex within TOUCH_SMOOTH_PX (itself included), as arrays from one query
    # between two trees: a list per vertex (query_ball_point) took twice as long, hundreds of neighbours each
    around = cKDTree(points[judged]).sparse_distance_matrix(cKDTree(points), TOUCH_SMOOTH_PX, output_type="ndarray")
    centre, near = around["i"].astype(np.int64), around["j"].astype(np.int64)
    own = ~apart_at_rest(at_rest, near, judged[centre])
    mean = np.zeros(len(shown))
    mean[judged] = (np.bincount(centre[own], weights=depth[near[own]], minlength=len(judged))
                    / np.bincount(centre[own], minlength=len(judged)))
    a, b = meet[:, 0], meet[:, 1]
    out[shown[a[mean[a] > mean[b] + TOUCH_MARGIN_M]]] = True
    out[shown[b[mean[b] > mean[a] + TOUCH_MARGIN_M]]] = True
    return out


def apart_at_rest(at_rest: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(P,) bool: points ``i`` and ``j`` (P,) lie more than TOUCH_APART_M apart at rest; ``at_rest`` (3, S) float32,
    one row per coordinate (float32, a coordinate at a time: this runs over up to a million pairs per frame)."""
    squared = np.zeros(len(i), np.float32)
    for coordinate in at_rest:
        step = coordinate.take(i) - coordinate.take(j)
        squared += step * step
    return squared > TOUCH_APART_M ** 2


# :func:`meeting_pairs` looks for pixel pairs closer than TOUCH_PX in square cells of that side: such a pair lies in
# one cell or in two touching ones, and two cells whose points all lie within TOUCH_APART_M of each other at rest (as
# their bounding boxes at rest show) hold no meeting pair. Most close pairs in a picture are neighbours on one surface
# (Anny's face and hands hold thousands of vertices in a few pixels), so few cells are left to search point by point.
CELL_NEIGHBOURS = ((0, 0), (1, -1), (1, 0), (1, 1), (0, 1))  # each unordered pair of touching cells once


def meeting_pairs(points: np.ndarray, at_rest: np.ndarray) -> np.ndarray:
    """Pairs of points within TOUCH_PX of each other in the picture and more than TOUCH_APART_M apart at rest
    (:func:`apart_at_rest`): where two surfaces of the body meet.

    Args:
        points: (S, 2) pixels; at_rest: (3, S) float32 the same points on the body at rest (metres).
    Returns:
        (P, 2) int64 indices into ``points``, each pair once, in no particular order.
    """
    cell = np.floor(np.asarray(points, np.float64) / TOUCH_PX).astype(np.int64)
    cell -= cell.min(axis=0) - 1  # columns and rows from 1, so a neighbour's key never wraps
    rows = int(cell[:, 1].max()) + 2
    key = cell[:, 0] * rows + cell[:, 1]
    order = np.argsort(key, kind="stable")
    keys, starts, counts = np.unique(key[order], return_index=True, return_counts=True)
    rest = at_rest.T.astype(np.float64)[order]  # (S, 3) in cell order
    low, high = np.minimum.reduceat(rest, starts), np.maximum.reduceat(rest, starts)  # (C, 3) boxes at rest
    first, second = [], []
    for dx, dy in CELL_NEIGHBOURS:
        other = keys + dx * rows + dy
        at = np.minimum(np.searchsorted(keys, other), len(keys) - 1)
        found = keys[at] == other
        first.append(np.flatnonzero(found))
        second.append(at[found])
    ca, cb = np.concatenate(first), np.concatenate(second)
    span = np.maximum(high[ca] - low[cb], high[cb] - low[ca])  # the farthest two of their points can lie per axis
    # a hair under the threshold: the boxes are bounds in float64, the pairs' own test runs in float32
    far = (span * span).sum(axis=1) > TOUCH_APART_M ** 2 * (1.0 - 1e-4)
    ca, cb = ca[far], cb[far]
    if len(ca) == 0:
        return np.zeros((0, 2), np.int64)
    # every point of cell ca[k] with every point of cell cb[k]
    na, nb = counts[ca], counts[cb]
    total = na * nb
    which = np.repeat(np.arange(len(ca)), total)
    k = np.arange(int(total.sum())) - np.repeat(np.cumsum(total) - total, total)
    i = order[starts[ca][which] + k // nb[which]]
    j = order[starts[cb][which] + k % nb[which]]
    once = (ca[which] != cb[which]) | (i < j)
    i, j = i[once], j[once]
    step = points[i] - points[j]
    close = (step * step).sum(axis=1) <= TOUCH_PX ** 2
    i, j = i[close], j[close]
    meet = apart_at_rest(at_rest, i, j)
    return np.stack([i[meet], j[meet]], axis=1)


def vertex_visibility(uvz: np.ndarray, depth: np.ndarray, *, tolerance: float | np.ndarray = VISIBILITY_TOLERANCE_M,
                      rest: np.ndarray | None = None) -> np.ndarray:
    """Which vertices are the front surface of a render.

    Args:
        uvz: (V, 3) projected vertices: pixel x, pixel y, depth in metres (:func:`core.camera.project`).
        depth: (H, W) the render's depth map (0 where nothing was drawn).
        tolerance: metres a vertex may lie behind the depth map and still count as seen: one for every vertex, or
            (V,) one per vertex.
        rest: (V, 3) the mesh's vertices on the body at rest, or None. Given, where two surfaces of the body meet
            in the picture only the front one counts as seen (:func:`behind_a_touching_surface`).
    Returns:
        (V,) bool.
    """
    h, w = depth.shape
    x = np.floor(uvz[:, 0]).astype(np.int64)
    y = np.floor(uvz[:, 1]).astype(np.int64)
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h) & (uvz[:, 2] > 0)
    seen = np.zeros(len(uvz), bool)
    d = depth[y[inside], x[inside]]
    allowed = np.broadcast_to(np.asarray(tolerance, np.float64), (len(uvz),))[inside]
    seen[inside] = (d > 0) & (uvz[inside, 2] <= d + allowed)
    if rest is not None:
        behind = np.zeros(len(uvz))
        behind[inside] = uvz[inside, 2] - d
        seen &= ~behind_a_touching_surface(uvz[:, :2], seen, behind, rest)
    return seen
