"""The reference appearance for the frame generator: the image, and the pose it shows.

The generator makes a frame by the analogy ``enc(x_ref) + enc(p_target) - enc(p_ref)``; it was trained on
pairs whose reference structure is exactly the structure of the reference frame. So the pipeline uses the
reference image's true pose when it is known, from a *reference pose file* beside the image
(``IMAGE.pose.npz``, see :func:`save_reference_pose`; the demo images have one, written by
``scripts/make_demo_inputs.py --reference``):

- body: ``points`` (17, 2), the image's canonical H36M-17 joints in its pixels;
- face: ``face`` (58,) parameters, ``identity`` and the camera that rendered the image.

Without one, a body reference gets its pose estimated (BlazePose, :mod:`motion2video.pose`; a note says
so), and a body reference where nobody is found is refused (InputError naming the picture): there is no person
to move. A person cut by the picture's edge gets a note; when the estimated joints themselves lie beyond the
edge, the picture is extended there (its edge repeated, :attr:`Reference.picture` marks those pixels as not the
file's) so that the pose fits in it; with ``keep_framing`` the extended picture is a larger canvas and
:attr:`Reference.view` the square the picture itself frames, which the frames are cut back to (:func:`framing_view`,
:func:`cut_to_view`), so a half-length portrait stays as large as it was pictured. A face reference without a
pose file (a photo or a painting of a face) gets the Anny head fitted to the face it shows (pose and expression,
:mod:`motion2video.pose.face_portrait`), and the square around that face, framed as the face generators' training
frames are, becomes the reference; one with no face is refused (InputError naming the picture). With the true or
fitted pose, the generated frames start from where the pictured face is.

"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np

from motion2video.core.atomic import save_npz
from motion2video.core.camera import affine_matrix
from motion2video.core.errors import InputError

REFERENCE_POSE_SUFFIX = ".pose.npz"
HAND_LANDMARKS = ("wrist", "index", "pinky", "thumb")  # BlazePose's points of each hand (ReferencePerson.hands)
PERSON_CROP_MARGIN = 0.1  # --crop-person: of the square's side, on every side
FRAMING_MIN_RATIO = 1.1  # a picture extended to hold its pose keeps its own framing when the canvas is this much larger
FRAMING_MAX_SIZE = 1024  # the largest canvas (px) generated on to keep a picture's framing


def reference_pose_path(image: str | Path) -> Path:
    """The reference pose file that goes with an image: ``ref.png`` -> ``ref.pose.npz``."""
    image = Path(image)
    return image.with_name(image.stem + REFERENCE_POSE_SUFFIX)


# --- the reference image and its pose --------------------------------------------------------------------

@dataclass(frozen=True)
class ReferencePose:
    """The pose shown in a reference image (see the module docstring).

    Attributes:
        kind: ``"body"`` or ``"face"``.
        width, height: size in pixels of the image the pose belongs to.
        points: body: (17, 2) canonical H36M-17 joints in image pixels (x right, y down); face: None.
        face: face: (58,) face parameters of the picture; body: None.
        identity: face: Anny phenotype values of the pictured face ({} = Anny's defaults).
        camera: face: the camera that rendered the picture (its size = width x height); body: None.
        face_shape: face, optional: (K,) the pictured face's shape, the coefficients of
            :mod:`motion2video.pose.face_shape`'s targets in [0, 1]: the head is drawn with it in every frame.
        camera_joints: body, optional: (17, 3) the pictured pose in 3D, in the picture camera's axes (metres; x
            right, y up, z away from the camera; any origin): BlazePose's world landmarks for a photo, the known
            pose for a render. The mesh generator's body fit takes its bone lengths and depth from it
            (:func:`motion2video.generator.mesh_fit.lift_reference`).
    """

    kind: str
    width: int
    height: int
    points: np.ndarray | None = None
    face: np.ndarray | None = None
    identity: dict = field(default_factory=dict)
    camera: object | None = None  # motion2video.core.camera.PinholeCamera
    camera_joints: np.ndarray | None = None
    face_shape: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("body", "face"):
            raise ValueError(f"kind must be 'body' or 'face', got {self.kind!r}")
        if self.kind == "body" and (self.points is None or np.asarray(self.points).shape != (17, 2)):
            raise ValueError("a body reference pose needs points of shape (17, 2)")
        if self.camera_joints is not None and (np.asarray(self.camera_joints).shape != (17, 3)
                                               or not np.all(np.isfinite(self.camera_joints))):
            raise ValueError("a body reference pose's camera_joints must be finite, of shape (17, 3)")
        if self.kind == "face" and (self.face is None or np.asarray(self.face).shape != (58,)
                                    or self.camera is None):
            raise ValueError("a face reference pose needs face params of shape (58,) and a camera")


def save_reference_pose(path: str | Path, pose: ReferencePose) -> Path:
    """Write a reference pose file (npz; atomically)."""
    path = Path(path)
    arrays: dict[str, np.ndarray] = {"kind": np.str_(pose.kind), "width": np.int64(pose.width),
                                     "height": np.int64(pose.height)}
    if pose.kind == "body":
        arrays["points"] = np.asarray(pose.points, np.float32)
        if pose.camera_joints is not None:
            arrays["camera_joints"] = np.asarray(pose.camera_joints, np.float32)
    else:
        cam = pose.camera
        arrays.update(face=np.asarray(pose.face, np.float32), identity=np.str_(json.dumps(pose.identity)),
                      camera_position=np.asarray(cam.position, np.float64),
                      camera_target=np.asarray(cam.target, np.float64), camera_yfov=np.float64(cam.yfov))
        if pose.face_shape is not None:
            arrays["face_shape"] = np.asarray(pose.face_shape, np.float64)
    return save_npz(path, arrays)


def load_reference_pose(path: str | Path) -> ReferencePose:
    """Read a reference pose file; InputError (naming it) when it is missing or malformed."""
    from motion2video.core.camera import PinholeCamera
    from motion2video.pose.face_shape import target_names

    path = Path(path)
    if not path.is_file():
        raise InputError("no such reference pose file", path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        kind = str(data["kind"])
        width, height = int(data["width"]), int(data["height"])
        if kind == "body":
            joints = data["camera_joints"].astype(np.float64) if "camera_joints" in data else None
            return ReferencePose(kind, width, height, points=data["points"].astype(np.float64), camera_joints=joints)
        if kind == "face":
            camera = PinholeCamera(tuple(float(v) for v in data["camera_position"]),
                                   tuple(float(v) for v in data["camera_target"]), float(data["camera_yfov"]),
                                   width, height)
            shape = data["face_shape"].astype(np.float64) if "face_shape" in data else None
            if shape is not None and (shape.shape != (len(target_names()),) or not np.all((shape >= 0) & (shape <= 1))):
                raise ValueError(f"face_shape must be {len(target_names())} values in [0, 1], got shape {shape.shape}")
            return ReferencePose(kind, width, height, face=data["face"].astype(np.float32),
                                 identity=json.loads(str(data["identity"])), camera=camera, face_shape=shape)
        raise ValueError(f"unknown kind {kind!r}")
    except (OSError, KeyError, ValueError, TypeError, json.JSONDecodeError) as err:
        raise InputError(f"not a valid reference pose file ({err})", path) from None


def read_reference_image(path: str | Path) -> tuple[np.ndarray, tuple[str, ...]]:
    """Read a reference image as RGB uint8, converting what can be converted, with a note for each.

    Conversions: grey -> RGB (replicated); grey + alpha and RGBA -> RGB composited over white; 16-bit ->
    8-bit.

    Returns:
        (H, W, 3) uint8 RGB and the notes.
    Raises:
        InputError: missing, empty or undecodable file, or an unsupported channel layout.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError("the reference is a folder, not an image file", path)
    if not path.is_file():
        raise InputError("no such reference image", path)
    data = np.fromfile(path, np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if image is None:
        raise InputError("cannot decode the reference image (not a PNG/JPEG/... image file)", path)
    notes = []
    if image.dtype == np.uint16:
        image = np.rint(image.astype(np.float64) / 257.0).astype(np.uint8)
        notes.append("16-bit image converted to 8-bit")
    elif image.dtype != np.uint8:
        raise InputError(f"unsupported reference image sample type {image.dtype}", path)
    if image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 1):
        image = np.repeat(image.reshape(image.shape[0], image.shape[1], 1), 3, axis=2)
        notes.append("grey-scale image converted to RGB")
    elif image.ndim == 3 and image.shape[2] == 2:  # grey + alpha
        grey, alpha = image[..., :1].astype(np.float64), image[..., 1:].astype(np.float64) / 255.0
        image = np.repeat(np.rint(grey * alpha + 255.0 * (1 - alpha)), 3, axis=2).astype(np.uint8)
        notes.append("grey-scale image with alpha converted to RGB over a white background")
    elif image.ndim == 3 and image.shape[2] == 4:
        rgb = image[..., 2::-1].astype(np.float64)  # BGRA -> RGB
        alpha = image[..., 3:].astype(np.float64) / 255.0
        image = np.rint(rgb * alpha + 255.0 * (1 - alpha)).astype(np.uint8)
        notes.append("RGBA image composited over a white background")
    elif image.ndim == 3 and image.shape[2] == 3:
        image = image[..., ::-1]  # BGR -> RGB
    else:
        raise InputError(f"unsupported reference image layout {image.shape}", path)
    return np.ascontiguousarray(image), tuple(notes)


def reference_alpha(path: str | Path) -> np.ndarray | None:
    """(H, W) float32 in [0, 1]: the alpha channel of a cut-out reference image (grey + alpha or RGBA, 8 or 16 bit)
    whose alpha is below one half somewhere; None for an image without alpha or opaque everywhere (an RGBA file
    whose alpha is 255 on every pixel is no cut-out). The caller has read the image (:func:`read_reference_image`)."""
    image = cv2.imdecode(np.fromfile(Path(path), np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None or image.ndim != 3 or image.shape[2] not in (2, 4):
        return None
    alpha = image[..., -1].astype(np.float32) / (65535.0 if image.dtype == np.uint16 else 255.0)
    return alpha if float(alpha.min()) < 0.5 else None


@dataclass(frozen=True)
class ImageFit:
    """How an image was made square and resized: ``out = in * scale + offset`` in pixels."""

    scale: float
    offset: tuple[float, float]
    padded: tuple[int, int]  # pixels added (left, top) before resizing


def fit_square(image: np.ndarray, size: int) -> tuple[np.ndarray, ImageFit]:
    """Pad an image to a square (centred, repeating its edge pixels), then resize it to size x size.

    Args:
        image: (H, W, 3) uint8.
    Returns:
        (size, size, 3) uint8 and the :class:`ImageFit` mapping input pixels to output pixels.
    """
    h, w = image.shape[:2]
    side = max(h, w)
    left, top = (side - w) // 2, (side - h) // 2
    if (h, w) != (side, side):
        image = cv2.copyMakeBorder(image, top, side - h - top, left, side - w - left, cv2.BORDER_REPLICATE)
    if side != size:
        interp = cv2.INTER_AREA if side > size else cv2.INTER_CUBIC
        image = cv2.resize(image, (size, size), interpolation=interp)
    scale = size / side
    return np.ascontiguousarray(image), ImageFit(scale, (left * scale, top * scale), (left, top))


def move_map(values: np.ndarray, scale: float, offset, size: tuple[int, int]) -> np.ndarray:
    """A per-pixel (H, W) map moved into a picture made by ``out = in * scale + offset`` (pixels), ``size`` = (W, H)
    of the new picture: float32, 0 where the new picture lies outside the old one. Bilinear both ways: OpenCV's
    ``warpAffine`` has no area mode (given ``INTER_AREA`` it interpolates linearly, as it did here until
    2026-11-26)."""
    mat = affine_matrix(scale, np.asarray(offset, np.float64))
    return cv2.warpAffine(np.asarray(values, np.float32), mat, (int(size[0]), int(size[1])),
                          flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)


@dataclass(frozen=True)
class ReferencePerson:
    """What the pose estimator found of the person in a reference picture, besides the pose.

    Found once in the picture as the user gave it, and moved with it through every cut, pad and zoom
    (:meth:`moved`), so that pixels the pipeline adds around a picture (a replicated border) are never the person.

    Attributes:
        mask: (H, W) float32 the person's probability per pixel (BlazePose's segmentation), 0 outside the picture.
        eyes: (2, 2) the left and right eye in pixels.
        eye_visibility: (2,) BlazePose's visibility of each eye.
        hands: (2, 4, 2) the left and right hand's :data:`HAND_LANDMARKS` in pixels.
        hand_visibility: (2, 4) BlazePose's visibility of each.
    """

    mask: np.ndarray
    eyes: np.ndarray
    eye_visibility: np.ndarray
    hands: np.ndarray
    hand_visibility: np.ndarray

    @staticmethod
    def of(person) -> "ReferencePerson":
        """From a :class:`motion2video.pose.estimate.PersonPose` found in an image."""
        from motion2video.pose.blazepose import LANDMARK_NAMES

        eyes = [LANDMARK_NAMES.index("left_eye"), LANDMARK_NAMES.index("right_eye")]
        hands = [[LANDMARK_NAMES.index(f"{side}_{name}") for name in HAND_LANDMARKS] for side in ("left", "right")]
        lm = person.landmarks
        xy, visibility = np.asarray(lm.xy, np.float64), np.asarray(lm.visibility, np.float64)
        return ReferencePerson(mask=lm.person_mask(person.width, person.height), eyes=xy[eyes, :2],
                               eye_visibility=visibility[eyes], hands=xy[np.array(hands), :2],
                               hand_visibility=visibility[np.array(hands)])

    def moved(self, scale: float, offset, size: tuple[int, int]) -> "ReferencePerson":
        """The same person in a picture made by ``out = in * scale + offset`` (pixels), ``size`` = (W, H) of the
        new picture; what lies outside the old picture is not the person."""
        offset = np.asarray(offset, np.float64)
        return replace(self, mask=move_map(self.mask, scale, offset, size),
                       eyes=np.asarray(self.eyes, np.float64) * scale + offset,
                       hands=np.asarray(self.hands, np.float64) * scale + offset)

    def segmented(self) -> np.ndarray:
        """(H, W) bool: the pixels that are more likely the person than not."""
        return np.asarray(self.mask) > 0.5


@dataclass(frozen=True)
class Reference:
    """The reference appearance at the generator's size.

    Attributes:
        image: (S, S, 3) uint8 RGB.
        pose: the reference pose moved into these pixels (camera resized to S x S), or None when unknown.
        notes: what was converted or assumed, one line each (the CLI prints them).
        path: the image file.
        person: the person's mask, eyes and hands in these pixels when the pose was estimated here (None with a
            pose file: the mesh generator then segments the image itself,
            :func:`motion2video.stages.generation.mesh_setup`).
        picture: (S, S) float32, 1 where these pixels come from the image file, 0 where a pad or zoom replicated its
            border (None: all of them come from it).
        source: (h, w, 3) uint8 the picture at the file's own resolution, after the cuts and pads but before the
            resize to S (None: ``image`` is the source); the face is taken from it
            (:func:`motion2video.stages.pictured_face.pictured_face`).
        source_scale, source_offset: ``image pixels = source pixels * source_scale + source_offset``.
        view: (x0, y0, side) the square of ``image`` the output frames show, in its pixels; None: all of it. Set
            when a person cut by the picture's edge (a half-length portrait) made the picture extend far past
            what it frames (:func:`framing_view`): ``image`` is then the extended canvas, larger than the output
            size, and the frames generated on it are cut to the view (:func:`cut_to_view`).
        relative_head: face: the head pose of the motion is applied relative to its first observed frame, on top of
            the reference's own (a fitted portrait keeps its pose and turns as the clip's head turns, rather than
            jumping to the clip's head pose; :func:`motion2video.stages.structure.relative_head_pose`).
    """

    image: np.ndarray
    pose: ReferencePose | None
    notes: tuple[str, ...]
    path: Path
    person: ReferencePerson | None = None
    picture: np.ndarray | None = None
    source: np.ndarray | None = None
    source_scale: float = 1.0
    source_offset: tuple[float, float] = (0.0, 0.0)
    relative_head: bool = False
    view: tuple[float, float, float] | None = None

    def picture_mask(self) -> np.ndarray:
        """(S, S) bool: the pixels that come from the image file (not a replicated border)."""
        if self.picture is None:
            return np.ones(self.image.shape[:2], bool)
        return np.asarray(self.picture) > 0.5


def _fit_pose(pose: ReferencePose, fit: ImageFit, size: int, image_shape: tuple[int, int]) -> ReferencePose:
    """A reference pose moved from the original image's pixels into the fitted square image's."""
    h, w = image_shape
    if pose.kind == "body":
        pts = np.asarray(pose.points, np.float64) * (w / pose.width, h / pose.height)  # stored size -> image
        return replace(pose, width=size, height=size, points=pts * fit.scale + np.asarray(fit.offset))
    # The padding is centred, so the principal point stays centred: only the vertical field of view of
    # the square changes when the width was the longer side.
    from motion2video.core.camera import PinholeCamera

    cam = pose.camera
    yfov = cam.yfov if h >= w else 2.0 * np.arctan(np.tan(0.5 * cam.yfov) * w / h)
    camera = PinholeCamera(cam.position, cam.target, float(yfov), size, size)
    return ReferencePose("face", size, size, face=pose.face, identity=dict(pose.identity), camera=camera)


def estimate_reference_pose(image: np.ndarray, path: str | Path
                            ) -> tuple[ReferencePose, ReferencePerson, np.ndarray] | tuple[None, None, None]:
    """The body pose of the largest person in an (H, W, 3) RGB image (BlazePose, :mod:`motion2video.pose`), that
    person's mask, eyes and hands, and their (33, 2) BlazePose body landmarks in pixels; (None, None, None) when
    nobody is found."""
    from motion2video.pose.blazepose import NUM_BODY_LANDMARKS
    from motion2video.pose.estimate import estimate_image

    try:
        person = estimate_image(image, source=path)
    except InputError:
        return None, None, None
    pose = ReferencePose("body", image.shape[1], image.shape[0], points=person.points2d,
                         camera_joints=person_camera_joints(person))
    landmarks = np.asarray(person.landmarks.xy[:NUM_BODY_LANDMARKS, :2], np.float64)
    return pose, ReferencePerson.of(person), landmarks


def person_camera_joints(person) -> np.ndarray:
    """(17, 3) an estimated person's canonical joints in the camera's axes (x right, y up, z away from the camera;
    hip-centred metres), from BlazePose's world landmarks."""
    from motion2video.pose.blazepose import NUM_BODY_LANDMARKS
    from motion2video.pose.h36m import blazepose_to_h36m, world_to_project

    world = person.landmarks.world[:NUM_BODY_LANDMARKS]
    project_axes, _ = blazepose_to_h36m(world_to_project(world[None]))  # (1, 17, 3): x right, y away, z up
    return project_axes[0][:, [0, 2, 1]].astype(np.float64)


# BlazePose landmark names -> the body part a note names (left and right together)
_PART_OF = {"nose": "head", "eye_inner": "head", "eye": "head", "eye_outer": "head", "ear": "head", "mouth": "head",
            "shoulder": "shoulders", "elbow": "elbows", "wrist": "hands", "pinky": "hands", "index": "hands",
            "thumb": "hands", "hip": "hips", "knee": "knees", "ankle": "feet", "heel": "feet", "foot_index": "feet"}
_EDGES = ("left", "top", "right", "bottom")


def cut_edges(landmarks: np.ndarray, *, width: int, height: int) -> dict[str, tuple[str, ...]]:
    """Where a person runs past a picture's edges: for each edge (``left``, ``top``, ``right``, ``bottom``) the
    body parts (``head``, ``hands``, ``knees``, ``feet``, ...) whose BlazePose landmarks lie beyond it.

    Args:
        landmarks: (33, 2) BlazePose body landmarks in the picture's pixels (the model places the ones it cannot
            see where the body would continue, outside the picture).
        width, height: the picture's size.
    Returns:
        {edge: parts}, only the edges something runs past; {} for a person wholly inside.
    """
    from motion2video.pose.blazepose import LANDMARK_NAMES

    xy = np.asarray(landmarks, np.float64)[:len(LANDMARK_NAMES)]
    beyond = {"left": xy[:, 0] < 0, "top": xy[:, 1] < 0, "right": xy[:, 0] >= width, "bottom": xy[:, 1] >= height}
    cut = {}
    for edge in _EDGES:
        names = [LANDMARK_NAMES[i].removeprefix("left_").removeprefix("right_") for i in np.flatnonzero(beyond[edge])]
        parts = tuple(dict.fromkeys(_PART_OF[n.removesuffix("_left").removesuffix("_right")] for n in names))
        if parts:
            cut[edge] = parts
    return cut


def pose_margins(points: np.ndarray, *, width: int, height: int) -> tuple[int, int, int, int]:
    """Pixels to add on each side (left, top, right, bottom) of a picture so that every joint of a body pose (17, 2)
    lies inside it, with 6 % of the pose's height to spare beyond each joint that was outside."""
    pts = np.asarray(points, np.float64)
    spare = 0.06 * max(float(np.ptp(pts[:, 1])), 1.0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    need = (-lo[0], -lo[1], hi[0] - width, hi[1] - height)
    return tuple(int(np.ceil(v + spare)) if v >= 0 else 0 for v in need)


def extend_to_pose(image: np.ndarray, pose: ReferencePose, margins: tuple[int, int, int, int]
                   ) -> tuple[np.ndarray, ReferencePose]:
    """A picture extended by ``margins`` (left, top, right, bottom) pixels, its edge repeated, and the body pose
    moved into it."""
    left, top, right, bottom = margins
    h, w = image.shape[:2]
    grown = cv2.copyMakeBorder(image, top, bottom, left, right, cv2.BORDER_REPLICATE)
    pts = np.asarray(pose.points, np.float64) * (w / pose.width, h / pose.height) + (left, top)
    return np.ascontiguousarray(grown), replace(pose, width=grown.shape[1], height=grown.shape[0], points=pts)


def cut_note(path: Path, cut: dict[str, tuple[str, ...]], margins: tuple[int, int, int, int]) -> str:
    """The one line that tells the user their reference person is cut by the picture's edge."""
    where = "; ".join(f"{', '.join(parts)} past the {edge} edge" for edge, parts in cut.items())
    grown = [f"{m} px {edge}" for edge, m in zip(_EDGES, margins) if m]
    how = (f"; the picture is extended ({', '.join(grown)}, its edge repeated) to hold the pose" if grown else "")
    return (f"the person in {path.name} is cut by the picture's edge ({where}): the frames guess what the picture "
            f"does not show{how}")


def crop_to_person(image: np.ndarray, pose: ReferencePose, *, margin: float = PERSON_CROP_MARGIN
                   ) -> tuple[np.ndarray, ReferencePose, tuple[int, int, int]]:
    """A square of ``image`` around the person of a body pose, and the pose moved into it.

    The square holds the joints' bounding box grown by 12% of the body's height above the head joint (the top
    of the head) and 6% below the lowest ankle (the feet), then ``margin`` of its larger side on every side. It
    is centred on the person, then moved (keeping that box inside) to take in as much of the image as it can:
    a person at an image's edge is not framed by a wide band of replicated border (``three_walking.jpg``: 124 px
    of border instead of 278, of a 789 px square). Outside the image the border is replicated.

    Returns:
        (side, side, 3) crop, its :class:`ReferencePose` and the box (x0, y0, side) in the image's pixels.
    """
    h, w = image.shape[:2]
    pts = np.asarray(pose.points, np.float64) * (w / pose.width, h / pose.height)
    x0, y0 = pts.min(axis=0)
    x1, y1 = pts.max(axis=0)
    tall = max(y1 - y0, 1.0)
    y0, y1 = y0 - 0.12 * tall, y1 + 0.06 * tall
    side = int(round(max(x1 - x0, y1 - y0) * (1 + 2 * margin)))
    left = _slide_into(int(round((x0 + x1 - side) / 2)), side, w, x0, x1)
    top = _slide_into(int(round((y0 + y1 - side) / 2)), side, h, y0, y1)
    pad = max(0, -left, -top, left + side - w, top + side - h)
    padded = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_REPLICATE) if pad else image
    crop = np.ascontiguousarray(padded[top + pad:top + pad + side, left + pad:left + pad + side])
    moved = replace(pose, width=side, height=side, points=pts - (left, top))
    return crop, moved, (left, top, side)


def _slide_into(start: int, side: int, length: int, lo: float, hi: float) -> int:
    """A square's first pixel along one axis, moved from ``start`` as little as needed so that [start, start + side)
    lies inside the image's [0, length) (or holds it whole when side > length), keeping the person's extent [lo, hi]
    inside the square; ``start`` unchanged when both cannot hold."""
    first = max(int(np.ceil(hi)) - side, min(0, length - side))
    last = min(int(np.floor(lo)), max(0, length - side))
    return int(np.clip(start, first, last)) if first <= last else start


def framing_view(picture: np.ndarray, person_mask: np.ndarray | None, *, crop_person: bool,
                 margin: float = PERSON_CROP_MARGIN) -> tuple[float, float, float]:
    """The square a picture frames, in the pixels of the picture extended to hold its person's pose.

    A half-length portrait's estimated legs lie far below its bottom edge, and the picture is extended to hold them
    (:func:`extend_to_pose`); framed around the whole pose, the pictured head and shoulders would fill a small part
    of the frame. The view is what the user framed instead. With ``crop_person``: the square around the part of the
    person the picture shows (``margin`` of its side on every side), no larger than the picture, so that no
    replicated border comes into view; when the shown person is taller than that square, it starts at their head.
    Without it: the picture's own square (centred, as :func:`fit_square` pads it).

    Args:
        picture: (H, W) the extended picture's map of the file's own pixels (> 0.5).
        person_mask: (H, W) the person's segmentation in the same pixels (> 0.5), or None.
        crop_person: frame the shown person rather than the whole picture.
    Returns:
        (x0, y0, side) in the extended picture's pixels.
    """
    file_pixels = np.asarray(picture) > 0.5
    ys, xs = np.nonzero(file_pixels)
    px0, py0, px1, py1 = xs.min(), ys.min(), xs.max() + 1, ys.max() + 1
    shown = None if person_mask is None else (np.asarray(person_mask) > 0.5) & file_pixels
    if not crop_person or shown is None or not shown.any():
        side = max(px1 - px0, py1 - py0)
        return float(px0 + (px1 - px0 - side) / 2), float(py0 + (py1 - py0 - side) / 2), float(side)
    ys, xs = np.nonzero(shown)
    x0, y0, x1, y1 = xs.min(), ys.min(), xs.max() + 1, ys.max() + 1
    side = min(max(x1 - x0, y1 - y0) * (1 + 2 * margin), px1 - px0, py1 - py0)
    left = (x0 + x1 - side) / 2
    top = (y0 + y1 - side) / 2 if (y1 - y0) * (1 + 2 * margin) <= side + 1e-6 else y0 - margin * side
    left, top = np.clip(left, px0, px1 - side), np.clip(top, py0, py1 - side)
    return float(left), float(top), float(side)


def cut_to_view(frames: np.ndarray, view: tuple[float, float, float] | None, size: int) -> np.ndarray:
    """Frames cut to a square view of theirs and resized to ``size`` (area-averaged when smaller).

    Args:
        frames: (..., S, S, 3) uint8, made at a reference's size.
        view: (x0, y0, side) in their pixels (:attr:`Reference.view`), or None (the frames are returned as they are).
        size: the output's side in pixels.
    Returns:
        (..., size, size, 3) uint8.
    """
    from motion2video.stages.pictured_face import cut_square

    if view is None:
        return frames
    x0, y0, side = (float(v) for v in view)
    square = (int(np.floor(x0)), int(np.floor(y0)), int(np.ceil(x0 + side)) - int(np.floor(x0)))
    inter = cv2.INTER_AREA if size < side else cv2.INTER_LINEAR
    flat = np.asarray(frames).reshape(-1, *frames.shape[-3:])
    out = np.stack([cv2.resize(cut_square(frame, square), (size, size), interpolation=inter) for frame in flat])
    return out.reshape(*frames.shape[:-3], size, size, 3)


def zoom_to_view(reference: "Reference", view: tuple[float, float, float]) -> "Reference":
    """A body reference re-framed to the square ``view`` (x0, y0, side) of its pixels, resized back to its size: a
    view larger than the picture zooms out, one beside it pans; outside the picture its border is replicated.

    Used to keep a motion that leaves the picture (a jump's head above the top) in view
    (:func:`motion2video.stages.structure.view_to_fit`). The pose, the person found in the picture and which
    pixels are the file's move with it; a note says what changed.
    """
    size = reference.image.shape[0]
    x0, y0, side = (float(v) for v in view)
    k = size / side
    image = cv2.warpAffine(reference.image, affine_matrix(k, -np.array([x0, y0]) * k), (size, size),
                           flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    pose = reference.pose
    if pose is not None:
        pts = (np.asarray(pose.points, np.float64) * (size / pose.width, size / pose.height) - (x0, y0)) * k
        pose = replace(pose, width=size, height=size, points=pts)
    person = None if reference.person is None else reference.person.moved(k, -np.array([x0, y0]) * k, (size, size))
    picture = move_map(np.ones((size, size)) if reference.picture is None else reference.picture, k,
                       -np.array([x0, y0]) * k, (size, size))
    note = (f"the motion leaves the reference picture: it is re-framed to the {side:.0f} px square at ({x0:.0f}, "
            f"{y0:.0f}) of its {size} px (scale {k:.2f}, the border replicated) so the person stays in view")
    shown = None if reference.view is None else (
        (reference.view[0] - x0) * k, (reference.view[1] - y0) * k, reference.view[2] * k)
    return Reference(image=np.ascontiguousarray(image), pose=pose, notes=reference.notes + (note,), path=reference.path,
                     person=person, picture=picture, view=shown,
                     source=reference.image if reference.source is None else reference.source,
                     source_scale=reference.source_scale * k,
                     source_offset=tuple((np.asarray(reference.source_offset) - [x0, y0]) * k))


def portrait_reference(image: np.ndarray, path: Path, *, size: int, notes: tuple[str, ...] = (),
                       pose_path: Path | None = None) -> Reference:
    """A face reference from a picture without a pose file: the Anny head fitted to its largest face (pose and
    expression, :func:`motion2video.pose.face_portrait.fit_portrait`) and the picture framed as the face frames
    are, ``size`` x ``size`` (:func:`~motion2video.pose.face_portrait.portrait_framing`), so the generated frames
    start from where the pictured face is. A note says what was fitted and cut.

    Args:
        image: (H, W, 3) uint8 RGB, the picture as read (:func:`read_reference_image`).
        path: its file (named by the note and the error); pose_path: the pose file that was looked for.
    Raises:
        InputError: no face in the picture.
    """
    from motion2video.pose.face_portrait import fit_portrait, frame_portrait, portrait_framing

    portrait = fit_portrait(image)
    if portrait is None:
        raise InputError("no face found in the reference image (face mesh detector): give a picture of a face, or "
                         "its pose with --reference-pose", path)
    framing = portrait_framing(portrait, size)
    framed, picture = frame_portrait(image, framing)
    pose = ReferencePose("face", size, size, face=portrait.params(), identity={}, camera=framing.camera,
                         face_shape=portrait.shape)
    x0, y0, side = framing.box()
    h, w = image.shape[:2]
    looked = f" ({pose_path.name})" if pose_path is not None else ""
    line = (f"no reference pose file{looked}: fitted the Anny head to the face in the image (face mesh; its landmarks "
            f"{100 * portrait.relative_error():.1f}% of the face size from the head's, median) and cut the "
            f"{side:.0f} px square at ({x0:.0f}, {y0:.0f}) of the {w}x{h} image around it, framed as the face frames "
            f"are, resized to {size}x{size}")
    if picture.min() <= 0.5:
        line += " (the square runs past the picture: its edge repeated)"
    extra = [f"{portrait.faces} faces in the image: the largest is the reference"] if portrait.faces > 1 else []
    return Reference(image=framed, pose=pose, notes=(*notes, line, *extra), path=path,
                     picture=None if picture.min() > 0.5 else picture, relative_head=True)


def load_reference(path: str | Path, *, size: int, domain: str,
                   pose_path: str | Path | None = None, crop_person: bool = False,
                   keep_framing: bool = False) -> Reference:
    """The reference image at ``size`` x ``size`` and its pose (see the module docstring).

    A body reference with no pose file gets its pose estimated (BlazePose, a note says so); a person cut by the
    picture's edge gets a note, and the picture is extended (its edge repeated) where the joints lie beyond it. A
    face reference with no pose file gets the Anny head fitted to its face and is cut around it
    (:func:`portrait_reference`; a note says so too).

    Args:
        path: the image.
        size: the generator's image size.
        domain: ``"body"`` or ``"face"`` (the pose file must be of this kind).
        pose_path: the reference pose file; None looks for ``IMAGE.pose.npz`` beside the image.
        crop_person: body: cut a square around the person first (:func:`crop_to_person`), so that a person
            small in a large photo fills the generator's frame.
        keep_framing: body, pose estimated here: when the picture had to be extended to hold its person's pose by
            more than a tenth (:data:`FRAMING_MIN_RATIO`: a half-length portrait), the reference is the extended
            canvas at a larger size (``size`` x canvas / view, at most :data:`FRAMING_MAX_SIZE`) and
            :attr:`Reference.view` the square the picture frames (:func:`framing_view`), so that frames cut to it
            (:func:`cut_to_view`) show the pictured person as large as the picture does. Only for generators that
            make frames of any size (the warp and mesh generators).
    Raises:
        InputError: unreadable image, a pose file that is malformed or of the other domain, no pose file and
        (body) no person or (face) no face found, a pose file with joints outside the image or no person, or an
        image that shows nothing along the pose's limbs; ``crop_person`` for a face model.
    """
    path = Path(path)
    image, notes = read_reference_image(path)
    notes = list(notes)
    if crop_person and domain != "body":
        raise InputError("--crop-person is for body references (this frame model makes face frames)", path)
    explicit = pose_path is not None
    pose_path = Path(pose_path) if explicit else reference_pose_path(path)
    pose, person = None, None
    from_file = explicit or pose_path.is_file()
    if from_file:
        pose = load_reference_pose(pose_path)
        if pose.kind != domain:
            raise InputError(f"this reference pose is a {pose.kind} pose, but the frame model makes {domain} "
                             "frames", pose_path)
    if not from_file and domain == "face":
        return portrait_reference(image, path, size=size, notes=tuple(notes), pose_path=pose_path)
    picture = np.ones(image.shape[:2], np.float32)  # which pixels are the file's, through every cut and pad
    view = None  # the square the picture frames, when it is kept (keep_framing)
    if not from_file and domain == "body":
        pose, person, landmarks = estimate_reference_pose(image, path)
        if pose is None:
            raise InputError("no person found in the reference image (BlazePose): give a picture of one person, or "
                             "its pose with --reference-pose", path)
        notes.append(f"no reference pose file ({pose_path.name}): estimated the person's pose in the image "
                     f"(BlazePose; `motion2video pose {path.name} -o {pose_path.name} --overlay check.png` "
                     "saves it and shows it)")
        alpha = reference_alpha(path)
        if alpha is not None:  # a cut-out's own matte is the person, sharper than a segmentation
            person = replace(person, mask=alpha)
            notes.append("the person is the image's alpha channel (a cut-out)")
        h0, w0 = image.shape[:2]
        cut = cut_edges(landmarks, width=w0, height=h0)
        margins = pose_margins(pose.points, width=w0, height=h0)
        if any(margins):
            image, pose = extend_to_pose(image, pose, margins)
            offset, grown = (margins[0], margins[1]), (image.shape[1], image.shape[0])
            picture = move_map(picture, 1.0, offset, grown)
            person = person.moved(1.0, offset, grown)
            if keep_framing:
                view = framing_view(picture, person.mask, crop_person=crop_person)
        if cut or any(margins):
            notes.append(cut_note(path, cut, margins))
    if crop_person:  # a body pose: from its file, or estimated above
        h0, w0 = image.shape[:2]
        image, pose, (left, top, side) = crop_to_person(image, pose)
        picture = move_map(picture, 1.0, (-left, -top), (side, side))
        if person is not None:
            person = person.moved(1.0, (-left, -top), (side, side))
        if view is not None:
            view = (view[0] - left, view[1] - top, view[2])
        notes.append(f"reference cut to the person: a {side}x{side} square at ({left}, {top}) of the {w0}x{h0} image")
    h, w = image.shape[:2]
    canvas = size
    if view is not None and max(h, w) < FRAMING_MIN_RATIO * view[2]:
        view = None  # the extension is small: the whole canvas is shown, as without keep_framing
    if view is not None:
        canvas = int(min(max(size, FRAMING_MAX_SIZE), round(size * max(h, w) / view[2])))
    fitted, fit = fit_square(image, canvas)
    if (h, w) != (canvas, canvas):
        how = f"padded to {max(h, w)}x{max(h, w)} and " if h != w else ""
        notes.append(f"reference image is {w}x{h}: {how}resized to {canvas}x{canvas} for the frame generator")
    picture = move_map(picture, fit.scale, fit.offset, (canvas, canvas))
    if person is not None:
        person = person.moved(fit.scale, fit.offset, (canvas, canvas))
    if view is not None:
        notes.append(f"the frames keep the picture's framing: they show the {view[2]:.0f} px square at "
                     f"({view[0]:.0f}, {view[1]:.0f}) of the {w}x{h} extended picture (the body is generated on all of "
                     f"it at {canvas}x{canvas}, the parts beyond the picture's edge out of view)")
        view = (view[0] * fit.scale + fit.offset[0], view[1] * fit.scale + fit.offset[1], view[2] * fit.scale)
    if pose is not None:
        pose = _fit_pose(pose, fit, canvas, (h, w))
        if domain == "body":  # a person to move: joints inside the image, and the image shows them
            from motion2video.generator.warp import check_reference_person, check_reference_points

            check_reference_points(pose.points, width=canvas, height=canvas, path=pose_path if from_file else path)
            check_reference_person(fitted, pose.points, path=path)
    return Reference(image=fitted, pose=pose, notes=tuple(notes), path=path, person=person,
                     picture=None if picture.min() > 0.5 else picture,
                     source=None if (h, w) == (canvas, canvas) else image,
                     source_scale=fit.scale, source_offset=tuple(float(v) for v in fit.offset), view=view)
