"""The pyrender mesh backend, the Anny body renderer and the Anny face renderer.

Everything renders for real through OSMesa with the real Anny model (built once per test session by
``renderers.anny_model.get_anny``); the body is checked on real mocap clips from ../shared/data/mocap
and the face on synthetic expressions and a real ARKit capture.
"""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES, FACE_DIM, FaceMotion, Motion
from renderers.mesh import as_unit_colors, vertex_normals

SIZE = 256


def test_vertex_normals_of_a_tetrahedron_point_outwards():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])  # counter-clockwise from outside
    normals = vertex_normals(vertices, faces)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)
    outward = vertices - vertices.mean(axis=0)
    assert np.all(np.sum(normals * outward, axis=1) > 0)
    # Apex (0, 0, 1): area-weighted face normals -y, -x and (1, 1, 1) sum to +z.
    np.testing.assert_allclose(normals[3], [0.0, 0.0, 1.0], atol=1e-6)


def test_colours_are_0_255_ints_or_unit_floats():
    np.testing.assert_allclose(as_unit_colors((255, 0, 51)), [1.0, 0.0, 0.2])
    np.testing.assert_allclose(as_unit_colors(np.array([0.5, 0.25, 1.0])), [0.5, 0.25, 1.0])
    assert as_unit_colors((10, 20, 30), count=4).shape == (4, 3)
    with pytest.raises(ValueError, match="0, 1"):
        as_unit_colors(np.array([2.0, 0.0, 0.0]))


# --- shared fixtures ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rest():
    from renderers import anny_model

    return anny_model.anny_rest()


@pytest.fixture(scope="module")
def body_renderer():
    from renderers.body import BodyRenderer, BodyStyle

    with BodyRenderer(BodyStyle(size=(SIZE, SIZE))) as renderer:
        yield renderer


def _rest_motion(rest, frames: int = 1) -> Motion:
    return Motion(np.repeat(rest.joints17[None], frames, axis=0).astype(np.float32), 25.0)


def _joint_coverage(joints: np.ndarray, masks: np.ndarray, camera, radius: int = 2) -> float:
    """Fraction of the in-view projected joints that fall on the silhouette or within ``radius`` px."""
    import cv2

    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    uvd = camera.project(joints)  # (T, 17, 3)
    hits = []
    for t in range(len(joints)):
        grown = cv2.dilate(masks[t].astype(np.uint8), disk) > 0
        for u, v, depth in uvd[t]:
            x, y = int(np.floor(u)), int(np.floor(v))
            if depth > 0 and 0 <= x < camera.width and 0 <= y < camera.height:
                hits.append(bool(grown[y, x]))
    assert hits, "no joint in view"
    return float(np.mean(hits))


# --- mesh backend ------------------------------------------------------------------------------------


@pytest.mark.slow
def test_mesh_render_is_deterministic_and_matches_the_camera_projection(rest):
    from renderers import anny_model
    from motion2video.core.camera import fit_camera
    from renderers.mesh import MeshRenderer

    renderer = MeshRenderer(SIZE, SIZE)
    camera = fit_camera(rest.vertices, SIZE, SIZE)
    colors = anny_model.vertex_colors(np.full((len(anny_model.REGION_NAMES), 3), 150, np.uint8), rest)
    a = renderer.render_mesh(rest.vertices, anny_model.triangles(), vertex_colors=colors, camera=camera,
                             background=(10, 20, 30))
    b = renderer.render_mesh(rest.vertices, anny_model.triangles(), vertex_colors=colors, camera=camera,
                             background=(10, 20, 30))
    assert a.color.dtype == np.uint8 and a.color.shape == (SIZE, SIZE, 3)
    np.testing.assert_array_equal(a.color, b.color)
    np.testing.assert_array_equal(a.mask, b.mask)
    assert 0.03 < a.mask.mean() < 0.5
    np.testing.assert_array_equal(a.color[~a.mask], np.broadcast_to([10, 20, 30], a.color[~a.mask].shape))
    assert np.all(a.depth[a.mask] > 0) and np.all(a.depth[~a.mask] == 0)
    # GL rasterisation and motion2video.core.camera.project agree: the mesh's bounding box in the image.
    uv = camera.project(rest.vertices)[:, :2]
    rows, cols = np.nonzero(a.mask)
    assert abs(cols.min() - uv[:, 0].min()) < 1.5 and abs(cols.max() + 1 - uv[:, 0].max()) < 1.5
    assert abs(rows.min() - uv[:, 1].min()) < 1.5 and abs(rows.max() + 1 - uv[:, 1].max()) < 1.5


@pytest.mark.slow
def test_failed_renders_raise(rest):
    from renderers import anny_model
    from motion2video.core.camera import fit_camera
    from renderers.mesh import MeshRenderer, RenderError

    renderer = MeshRenderer(SIZE, SIZE)
    camera = fit_camera(rest.vertices, SIZE, SIZE)
    faces = anny_model.triangles()
    # Degenerate geometry in front of the camera rasterises to nothing: an empty frame must not pass.
    collapsed = np.broadcast_to(rest.vertices.mean(axis=0), rest.vertices.shape)
    with pytest.raises(RenderError, match="empty"):
        renderer.render_mesh(collapsed, faces, vertex_colors=(200, 200, 200), camera=camera)
    # Another GL platform cannot be used once OpenGL is set up in this process.
    with pytest.raises(RenderError, match="already initialised"):
        MeshRenderer(SIZE, SIZE, platform="egl").render_mesh(rest.vertices, faces, vertex_colors=(1, 2, 3),
                                                             camera=camera)
    with pytest.raises(ValueError, match="camera is"):
        renderer.render_mesh(rest.vertices, faces, vertex_colors=(1, 2, 3), camera=camera.with_size(64, 64))
    with pytest.raises(ValueError, match="NaN"):
        renderer.render_mesh(np.full_like(rest.vertices, np.nan), faces, vertex_colors=(1, 2, 3), camera=camera)


@pytest.mark.slow
def test_one_gl_renderer_is_shared_and_compiles_its_shader_once(rest, body_renderer):
    from renderers.body import BodyRenderer, BodyStyle
    from renderers.face import FaceRenderer, FaceStyle

    other = BodyRenderer(BodyStyle(size=(SIZE, SIZE), top=(200, 30, 30)))
    face = FaceRenderer(FaceStyle(size=(SIZE, SIZE)))
    assert other.offscreen is body_renderer.offscreen is face.offscreen
    motion = _rest_motion(rest, frames=3)
    body_renderer.render(motion)
    other.render(motion)
    # pyrender keys its shader cache by a ctypes pointer that changes every call under OSMesa; our cache
    # keeps one program for all these frames.
    assert len(body_renderer.offscreen._renderer._program_cache) == 1


# --- body --------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_body_front_view_faces_the_camera_with_its_left_on_the_image_right(rest, body_renderer):
    result = body_renderer.render_with_masks(_rest_motion(rest))
    frame, mask = result.frames[0], result.masks[0]
    uv = result.camera.project(rest.joints17)  # (17, 3)
    left_wrist, right_wrist = uv[13], uv[16]
    assert left_wrist[0] > SIZE / 2 > right_wrist[0]
    # Mesh and joints line up; the whole body is in the picture with a margin.
    assert _joint_coverage(rest.joints17[None], result.masks, result.camera, radius=0) == 1.0
    rows, cols = np.nonzero(mask)
    assert rows.min() > 3 and rows.max() < SIZE - 4 and cols.min() > 3 and cols.max() < SIZE - 4
    # Face to the camera: the skin of the face shows between the eyes' pixels (iris is dark).
    skin = np.array(body_renderer.style.skin, float)
    head = result.camera.project(rest.bone_heads[101])  # the "head" bone, base of the skull
    face_px = frame[int(head[1]) - 6, int(head[0])].astype(float)
    assert np.abs(face_px - skin).max() < 80, face_px
    # Renders are deterministic.
    np.testing.assert_array_equal(body_renderer.render(_rest_motion(rest)), result.frames)


@pytest.mark.slow
@pytest.mark.parametrize("clip", [
    "cmu/01_01.bvh",  # cmu-mb: jumps, turn around
    "cmu/131_03.bvh",  # cmu-3dsmax: hop
    "cmu/05_14.bvh",  # cmu-daz: dance
    "deepmimic/humanoid3d_cartwheel.bvh",  # deepmimic: upside down
    "mass/mass_kick.bvh",  # mass
])
def test_silhouette_covers_the_clip_joints(mocap_dir, body_renderer, clip):
    from motion2video.formats.bvh import load_bvh

    motion = load_bvh(mocap_dir / clip, manifest=True, target_fps=25)
    frames = np.linspace(0, motion.num_frames - 1, 8).astype(int)
    sub = Motion(motion.joints[frames], motion.fps, source=motion.source)
    seen = []
    result = body_renderer.render_with_masks(sub, progress=seen.append)
    assert sum(seen) == 8
    assert result.frames.shape == (8, SIZE, SIZE, 3) and result.frames.dtype == np.uint8
    assert result.masks.any(axis=(1, 2)).all()
    coverage = _joint_coverage(sub.joints, result.masks, result.camera)
    assert coverage >= 0.95, f"{clip}: only {coverage:.1%} of the joints fall on the silhouette"


@pytest.mark.slow
def test_body_renderer_inputs(rest, body_renderer):
    from renderers.body import BodyRenderer, BodyStyle

    flat = Motion(np.zeros((2, 17, 2), np.float32), 25.0)
    with pytest.raises(InputError, match="3D h36m-17"):
        body_renderer.render(flat)
    with pytest.raises(InputError, match="phenotype"):
        BodyRenderer(BodyStyle(phenotype={"wingspan": 0.5}))
    # A background image shows where the body is not; a given camera is used as it is.
    background = np.zeros((96, 64, 3), np.uint8)
    background[..., 1] = 255
    small = BodyRenderer(BodyStyle(size=(64, 96), background=background, phenotype={"height": 0.2}))
    result = small.render_with_masks(_rest_motion(rest))
    assert result.frames.shape == (1, 96, 64, 3)
    np.testing.assert_array_equal(result.frames[0][~result.masks[0]],
                                  background[~result.masks[0]])
    again = small.render_with_masks(_rest_motion(rest), camera=result.camera)
    np.testing.assert_array_equal(again.frames, result.frames)


# --- face --------------------------------------------------------------------------------------------


def _face(rows: list[dict[str, float]]) -> FaceMotion:
    """A FaceMotion from per-frame {ARKit name or 'yaw'/'pitch': value} dicts."""
    params = np.zeros((len(rows), FACE_DIM), np.float32)
    for t, row in enumerate(rows):
        for name, value in row.items():
            if name == "pitch":
                params[t, 52] = value
            elif name == "yaw":
                params[t, 54] = value
            else:
                params[t, ARKIT_NAMES.index(name)] = value
    return FaceMotion(params, 30.0)


@pytest.fixture(scope="module")
def face_renderer():
    from renderers.face import FaceRenderer, FaceStyle

    with FaceRenderer(FaceStyle(size=(SIZE, SIZE))) as renderer:
        yield renderer


def _box_diff(a: np.ndarray, b: np.ndarray, centre: np.ndarray, half: int) -> float:
    """Mean absolute pixel difference in a square box around ``centre`` (x, y)."""
    x, y = int(centre[0]), int(centre[1])
    box = (slice(max(y - half, 0), y + half), slice(max(x - half, 0), x + half))
    return float(np.abs(a[box].astype(float) - b[box].astype(float)).mean())


@pytest.mark.slow
def test_expressions_visibly_change_their_region(rest, face_renderer):
    from renderers import anny_model

    face = _face([{}, {"jawOpen": 1.0}, {"mouthSmileLeft": 1.0, "mouthSmileRight": 1.0},
                  {"eyeBlinkLeft": 1.0, "eyeBlinkRight": 1.0}])
    result = face_renderer.render_with_masks(face)
    neutral, jaw, smile, blink = result.frames
    camera = result.camera
    lips = camera.project(rest.vertices[anny_model.lip_weights(rest) > 0.5])[:, :2].mean(axis=0)
    eyes = camera.project(rest.bone_heads[[anny_model.bone_index("eye.L"), anny_model.bone_index("eye.R")]])
    forehead = camera.project(rest.bone_heads[anny_model.bone_index("head")] + [0, -0.1, 0.1])
    # Each expression changes its own region clearly, and the forehead hardly at all.
    assert _box_diff(neutral, jaw, lips + [0, 10], 20) > 15
    assert _box_diff(neutral, smile, lips, 24) > 8
    for eye in eyes:
        assert _box_diff(neutral, blink, eye, 8) > 10
    for other in (jaw, smile, blink):
        assert _box_diff(neutral, other, forehead, 10) < 1.0
    np.testing.assert_array_equal(face_renderer.render(face), result.frames)  # deterministic


@pytest.mark.slow
def test_head_pose_turns_and_nods_the_head(rest, face_renderer):
    from renderers import anny_model

    face = _face([{}, {"yaw": 0.5}, {"pitch": 0.4}])
    result = face_renderer.render_with_masks(face)
    nose = int(np.argmin(np.where(anny_model.dominant_bones() == anny_model.bone_index("head"),
                                  rest.vertices[:, 1], np.inf)))  # the front-most head vertex
    head = face_renderer._head_mesh(face)
    position = list(head.vertex_ids).index(nose)
    (_, verts), = list(face_renderer.vertices(face))
    nose_px = result.camera.project(verts[:, position])  # (3, 3)
    # +yaw turns the face to its left = the image's right; +pitch nods it down.
    assert nose_px[1, 0] - nose_px[0, 0] > 15
    assert nose_px[2, 1] - nose_px[0, 1] > 10
    centroid = [np.argwhere(m)[:, 1].mean() for m in result.masks]
    assert centroid[1] > centroid[0]


@pytest.mark.slow
def test_face_landmarks_follow_the_mesh(face_renderer):
    from renderers.face import FACE_LANDMARK_NAMES

    seen = []
    result = face_renderer.render_with_masks(_face([{}, {"jawOpen": 1.0}, {"yaw": 0.4}]), progress=seen.append)
    assert sum(seen) == 3
    lm = result.landmarks  # (3, K, 2)
    assert lm.shape == (3, len(FACE_LANDMARK_NAMES), 2)
    name = {n: i for i, n in enumerate(FACE_LANDMARK_NAMES)}
    neutral = lm[0]
    # Anatomical order in the image (y down; the face's right on the image's left).
    assert neutral[name["right_eye"], 0] < neutral[name["nose_tip"], 0] < neutral[name["left_eye"], 0]
    assert (neutral[name["right_eye"], 1] < neutral[name["nose_tip"], 1] < neutral[name["upper_lip"], 1]
            < neutral[name["lower_lip"], 1] < neutral[name["chin"], 1])
    assert neutral[name["right_mouth_corner"], 0] < neutral[name["left_mouth_corner"], 0]
    # Every landmark of the neutral face lies on the silhouette.
    assert all(result.masks[0][int(y), int(x)] for x, y in neutral)
    # Opening the jaw lowers the lower lip and chin, not the eyes; turning moves the nose.
    for moved in ("lower_lip", "chin"):
        assert lm[1, name[moved], 1] - neutral[name[moved], 1] > 10
    assert np.abs(lm[1, name["left_eye"]] - neutral[name["left_eye"]]).max() < 1.0
    assert lm[2, name["nose_tip"], 0] - neutral[name["nose_tip"], 0] > 10


@pytest.mark.slow
def test_structure_style_is_uniform_grey_and_real_captures_render(face_dir, rest):
    from motion2video.data.face_data import load_face_clip
    from renderers.face import FaceRenderer, FaceStyle

    face = load_face_clip(face_dir / "llv" / "dao.csv").slice(0, 40)
    face = FaceMotion(face.params[::13], face.fps, source=face.source)  # 4 frames spread over the take
    structure = FaceRenderer(FaceStyle(size=(128, 128), style="structure")).render_with_masks(face)
    pixels = structure.frames[structure.masks].astype(int)  # (N, 3)
    assert len(pixels) > 0.2 * structure.masks[0].size
    assert np.abs(pixels[:, 0] - pixels[:, 1]).max() <= 1 and np.abs(pixels[:, 1] - pixels[:, 2]).max() <= 1
    assert pixels[:, 0].std() > 5  # shaded, not flat
    # The real take moves: consecutive frames differ.
    diffs = np.abs(np.diff(structure.frames.astype(float), axis=0)).mean(axis=(1, 2, 3))
    assert np.all(diffs > 0.05), diffs
    with pytest.raises(InputError, match="identity"):
        FaceRenderer(FaceStyle(size=(64, 64))).render(FaceMotion(face.params, 30.0, identity={"nose": 1.0}))
    with pytest.raises(InputError, match="face style"):
        FaceRenderer(FaceStyle(style="cartoon"))


@pytest.mark.slow
def test_released_renderers_are_recreated_on_demand(rest, body_renderer):
    from renderers.mesh import release_renderers

    before = body_renderer.offscreen
    frame = body_renderer.render(_rest_motion(rest))
    release_renderers()
    after = body_renderer.offscreen
    assert after is not before
    np.testing.assert_array_equal(body_renderer.render(_rest_motion(rest)), frame)


@pytest.mark.parametrize("seed", range(6))
def test_meeting_pairs_are_the_close_pairs_far_apart_at_rest(seed):
    """The cell search finds exactly the pairs a KD-tree finds within TOUCH_PX and TOUCH_APART_M filters: dense
    clusters of one surface (as a face's vertices lie) beside clusters of another, on and off the cells' edges."""
    from scipy.spatial import cKDTree

    from renderers.mesh import TOUCH_PX, apart_at_rest, meeting_pairs

    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 40, (12, 2))
    points = np.concatenate([c + rng.normal(0, rng.uniform(0.3, 3.0), (150, 2)) for c in centres])
    points[::7] = np.round(points[::7] / TOUCH_PX) * TOUCH_PX  # some exactly on cell edges
    surface = np.repeat(rng.uniform(-0.5, 0.5, (12, 3)), 150, axis=0)  # each cluster a place on the body
    at_rest = np.ascontiguousarray((surface + rng.normal(0, 0.03, surface.shape)).T.astype(np.float32))
    close = cKDTree(points).query_pairs(TOUCH_PX, output_type="ndarray")
    expected = close[apart_at_rest(at_rest, close[:, 0], close[:, 1])]
    found = meeting_pairs(points, at_rest)
    assert len(expected) > 0 and len(found) == len(expected)
    assert set(map(tuple, np.sort(found, axis=1).tolist())) == set(map(tuple, np.sort(expected, axis=1).tolist()))
