"""The multimodal future-video pipeline (motion2video.apps.synthesize): its pure geometry, the reference image and
pose handling, the cached-reference generator path, and end to end on tiny checkpoints trained here
(motion models through the `train` CLI on real clips, frame generators by the real training loop on the toy
set) with the committed demo inputs and reference images."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import cv2
import imageio.v3 as iio
import numpy as np
import pytest
import torch

from motion2video.apps.synthesize import (
    SynthesisConfig, compose_chunk, compose_video, contact_sheet, contact_sheet_of, output_paths, render_mesh_frames,
    synthesize,
)
from motion2video.stages.structure import face_camera_front, follow_on_ground, place_body, similarity_fit
from motion2video.stages.generation import generate_frames
from motion2video.stages import reference as R
from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.formats.video import GREEN, RED, read_image, read_video

REPO = Path(__file__).resolve().parents[1]
DEMO = REPO / "demo_inputs"
FRAME_SIZE = 64
BODY_CLIPS = ("cmu/131_01.bvh", "cmu/131_02.bvh", "cmu/01_01.bvh")
TINY_MOTION = json.dumps({"model": {"hidden_dim": 8, "latent_dim": 4, "mlp_dim": 8},
                          "train": {"batch_size": 4, "checkpoint_every": 2, "val_every": 2, "val_windows": 8}})


# --- tiny checkpoints (plain functions, also used by test_synthesize_cli.py) -----------------------------

def train_body_motion_model(mocap_dir: Path, folder: Path) -> Path:
    """A 2-step mtvae-add on three real BVH clips, trained through the CLI."""
    data = folder / "mocap"
    for rel in BODY_CLIPS:
        (data / rel).parent.mkdir(parents=True, exist_ok=True)
        (data / rel).symlink_to(mocap_dir / rel)
    out = folder / "body.safetensors"
    assert main(["train", "--model", "mtvae-add", "--data", str(data), "-o", str(out), "--steps", "2",
                 "--config", TINY_MOTION, "--no-progress"]) == 0
    return out


def train_dlow_model(base: Path) -> Path:
    """A 2-step DLow sampler over the tiny body model ``base`` (the demo draws the best sampler's futures),
    trained through the CLI on the body clips already linked by :func:`train_body_motion_model`."""
    out = base.parent / "dlow.safetensors"
    config = json.dumps({"model": {"num_samples": 6, "hidden_dim": 8},
                         "train": {"batch_size": 4, "checkpoint_every": 5, "val_every": 5, "val_windows": 8}})
    assert main(["train", "--model", "dlow", "--base", str(base), "--data", str(base.parent / "mocap"), "-o",
                 str(out), "--steps", "2", "--config", config, "--no-progress"]) == 0
    return out


def train_behavior_model(folder: Path) -> Path:
    """A 2-step behaviour model (root-trajectory decoder) on the body clips already linked by
    :func:`train_body_motion_model`, trained through the CLI (the demo's transfer)."""
    out = folder / "behavior.safetensors"
    config = ('{"model": {"hidden_dim": 16, "latent_dim": 4, "regressor_dim": 16, "root_trajectory": true}, '
              '"train": {"flow_steps": 5, "flow_windows": 16}}')
    assert main(["train", "--model", "behavior", "--data", str(folder / "mocap"), "-o", str(out), "--steps", "2",
                 "--config", config, "--no-progress"]) == 0
    return out


def train_face_motion_model(face_dir: Path, folder: Path) -> Path:
    """A 2-step mtvae-add on one real ARKit capture, trained through the CLI."""
    out = folder / "face.safetensors"
    assert main(["train", "--model", "mtvae-add", "--data", str(face_dir / "llv" / "dao.csv"), "-o", str(out),
                 "--steps", "2", "--config", TINY_MOTION, "--no-progress"]) == 0
    return out


def train_frame_model(domain: str, folder: Path) -> Path:
    """A tiny 64 px generator trained for 2 steps on the toy set by the real training loop."""
    from motion2video.generator.data import structure_channels, toy_sequences
    from motion2video.generator.model import FrameGeneratorConfig
    from motion2video.generator.training import TrainFramesConfig, train_frames

    seqs = toy_sequences(domain, num_sequences=2, frames_per_sequence=3, image_size=FRAME_SIZE)
    config = FrameGeneratorConfig(domain=domain, image_size=FRAME_SIZE, structure_channels=structure_channels(domain),
                                  channels=(8, 12, 16))
    result = train_frames(seqs, output=folder / f"frames_{domain}.safetensors",
                          config=TrainFramesConfig(steps=2, batch_size=2, warmup_steps=1, checkpoint_every=2,
                                                   log_every=1),
                          model_config=config, progress=False)
    return Path(result.path)


def border_colour(frame: np.ndarray, cell: int, *, size: int = FRAME_SIZE, columns: int, gap: int = 2) -> np.ndarray:
    """Mean RGB of the middle of a grid cell's top border strip (rows 1-2)."""
    r, c = divmod(cell, columns)
    y, x = r * (size + gap), c * (size + gap)
    return frame[y + 1:y + 3, x + size // 3:x + 2 * size // 3].reshape(-1, 3).mean(axis=0)


def assert_framed(frames: np.ndarray, *, observed: int, cells: int, columns: int, size: int = FRAME_SIZE) -> None:
    """Observed frames of every cell have a green border, the rest a red one (after H.264: tolerances)."""
    green, red = np.array(GREEN, float), np.array(RED, float)
    for t in (0, observed - 1, observed, len(frames) - 1):
        want = green if t < observed else red
        for cell in range(cells):
            colour = border_colour(frames[t], cell, size=size, columns=columns)
            assert np.abs(colour - want).max() < 40, (t, cell, colour)


@pytest.fixture(scope="module")
def checkpoints(tmp_path_factory, mocap_dir) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("pipeline_ckpt")
    return {"body": train_body_motion_model(mocap_dir, folder), "frames_body": train_frame_model("body", folder)}


# --- pure parts ---------------------------------------------------------------------------------------

def test_output_names():
    assert output_paths("out/x.mp4") == (Path("out/x.mp4"), Path("out/x-structure.mp4"), Path("out/x-sheet.png"))
    assert R.reference_pose_path("a/ref.png") == Path("a/ref.pose.npz")


def test_similarity_fit_recovers_scale_and_shift():
    rng = np.random.default_rng(0)
    src = rng.normal(size=(11, 2))
    scale, shift = similarity_fit(src, src * 2.5 + [3.0, -4.0])
    assert scale == pytest.approx(2.5) and np.allclose(shift, [3.0, -4.0])


def test_front_facing_and_following_the_pelvis():
    joints = np.load(DEMO / "walk_to_run.npz")["joints"][:40].astype(np.float64)  # walks towards -y
    turned = joints @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).T  # now faces +x
    front = face_camera_front(turned)
    hips = front[0, 4] - front[0, 1]  # right hip -> left hip
    assert hips[0] > 0 and abs(hips[1]) < 1e-6  # the body's left is +x: it faces -y
    np.testing.assert_allclose(np.linalg.norm(front - front[:, :1], axis=-1),
                               np.linalg.norm(turned - turned[:, :1], axis=-1), atol=1e-9)  # rigid
    followed = follow_on_ground(front)
    np.testing.assert_allclose(followed[:, 0, :2], np.repeat(front[:1, 0, :2], 40, axis=0), atol=1e-9)
    np.testing.assert_allclose(followed[..., 2], front[..., 2])  # heights kept


def test_body_placement_puts_the_reference_pose_on_the_reference_picture():
    """The first observed frame is the pose the demo reference shows: after placement it lands on the
    reference pose file's joints (this fails if left/right, y-down or the scale were wrong)."""
    joints = np.load(DEMO / "walk_to_run.npz")["joints"].astype(np.float64)
    ref = R.load_reference_pose(DEMO / "reference_body_128.pose.npz")
    placed = place_body(joints[:8], np.stack([joints[8:14], joints[8:14] + [0.0, 0.0, 0.2]]), size=128,
                          reference_points=ref.points)
    err = np.linalg.norm(placed.observed[0] - ref.points, axis=-1)
    assert err.max() < 2.0, err  # pixels at 128 (only the perspective of the two cameras differs)
    assert placed.futures.shape == (2, 6, 17, 2)
    assert placed.observed[0, 14, 0] < placed.observed[0, 11, 0]  # right shoulder on the image's left
    # The lifted future is drawn higher (smaller y) by about the same lift in pixels everywhere.
    lift = placed.futures[0, :, :, 1] - placed.futures[1, :, :, 1]
    assert lift.min() > 0
    # Without a reference pose the first frame is framed like a single-frame render: centred and inside.
    alone = place_body(joints[:8], joints[None, 8:14], size=128)
    assert np.all((alone.reference > 0) & (alone.reference < 128))
    np.testing.assert_allclose(alone.observed[0].mean(0), alone.reference.mean(0), atol=1.5)


def test_reference_image_conversions(tmp_path):
    rgb = np.zeros((40, 30, 3), np.uint8)
    rgb[..., 0], rgb[..., 1], rgb[..., 2] = 200, 100, 50
    cases = {
        "grey.png": (np.full((40, 30), 90, np.uint8), (90, 90, 90), "grey-scale"),
        "grey_alpha.png": (np.dstack([np.full((40, 30), 0, np.uint8), np.full((40, 30), 0, np.uint8)]),
                           (255, 255, 255), "white"),
        "rgba.png": (np.dstack([rgb[..., ::-1], np.full((40, 30), 255, np.uint8)]), (200, 100, 50), "RGBA"),
        "clear.png": (np.dstack([rgb[..., ::-1], np.zeros((40, 30), np.uint8)]), (255, 255, 255), "RGBA"),
        "deep.png": (np.full((40, 30, 3), 65535, np.uint16), (255, 255, 255), "16-bit"),
        "plain.png": (rgb[..., ::-1], (200, 100, 50), None),
    }
    for name, (array, colour, note) in cases.items():
        if array.ndim == 3 and array.shape[2] == 2:  # grey + alpha: OpenCV cannot write it, Pillow can
            iio.imwrite(tmp_path / name, array)
        else:
            assert cv2.imwrite(str(tmp_path / name), array)
        image, notes = R.read_reference_image(tmp_path / name)
        assert image.shape == (40, 30, 3) and image.dtype == np.uint8, name
        assert tuple(image[20, 15]) == colour, name
        assert (note is None and not notes) or any(note in n for n in notes), (name, notes)
    (tmp_path / "text.png").write_text("not an image")
    (tmp_path / "empty.png").write_bytes(b"")
    for name, message in (("missing.png", "no such"), ("text.png", "cannot decode"), ("empty.png", "cannot decode")):
        with pytest.raises(InputError, match=message) as err:
            R.read_reference_image(tmp_path / name)
        assert name in str(err.value) and "\n" not in str(err.value)


def test_non_square_reference_is_padded_and_its_pose_follows(tmp_path):
    image = np.full((60, 100, 3), 255, np.uint8)
    points = np.tile([[70.0, 20.0]], (17, 1))
    points[0] = [30.5, 40.5]
    cv2.circle(image, (30, 40), 3, (0, 0, 255), -1)  # a red dot (BGR) at joint 0
    cv2.imwrite(str(tmp_path / "wide.png"), image)
    R.save_reference_pose(tmp_path / "wide.pose.npz", R.ReferencePose("body", 100, 60, points=points))
    ref = R.load_reference(tmp_path / "wide.png", size=50, domain="body")
    assert ref.image.shape == (50, 50, 3)
    assert any("padded to 100x100 and resized to 50x50" in n for n in ref.notes)
    x, y = ref.pose.points[0]
    assert (x, y) == pytest.approx((30.5 * 0.5, (40.5 + 20) * 0.5))
    assert ref.image[int(y), int(x), 0] > 200 and ref.image[int(y), int(x), 1] < 80  # the dot is there
    with pytest.raises(InputError, match="body pose, but the frame model makes face"):
        R.load_reference(tmp_path / "wide.png", size=50, domain="face")
    (tmp_path / "bad.pose.npz").write_bytes(b"junk")
    with pytest.raises(InputError, match="not a valid reference pose file"):
        R.load_reference(tmp_path / "wide.png", size=50, domain="body", pose_path=tmp_path / "bad.pose.npz")
    face = R.load_reference(DEMO / "reference_face.png", size=64, domain="face")  # its pose file is found
    assert face.pose.camera.width == 64 and face.pose.camera.yfov == R.load_reference_pose(
        DEMO / "reference_face.pose.npz").camera.yfov


def test_face_reference_pose_round_trip(tmp_path):
    pose = R.load_reference_pose(DEMO / "reference_face.pose.npz")
    assert pose.kind == "face" and pose.face.shape == (58,) and pose.camera.width == 256
    path = R.save_reference_pose(tmp_path / "f.pose.npz", pose)
    again = R.load_reference_pose(path)
    np.testing.assert_array_equal(again.face, pose.face)
    assert again.camera == pose.camera and again.identity == pose.identity


@pytest.mark.parametrize("channels_last", [False, True])
def test_cached_reference_generation_matches_the_model(channels_last):
    """generate_frames encodes the reference once; its frames equal the model's own forward pass."""
    from motion2video.generator.model import FrameGenerator, FrameGeneratorConfig, generate

    torch.manual_seed(0)
    for output in ("residual", "direct"):
        net = FrameGenerator(FrameGeneratorConfig(image_size=32, channels=(8, 12, 16), output=output))
        torch.nn.init.normal_(net.decoder.head.weight, std=0.05)
        rng = np.random.default_rng(1)
        ref = rng.integers(0, 256, (32, 32, 3), dtype=np.uint8)
        ref_s = rng.random((33, 32, 32), dtype=np.float32)
        tgt = rng.random((5, 33, 32, 32), dtype=np.float32)
        ours = generate_frames(net, ref, ref_s, tgt, batch_size=2, channels_last=channels_last)
        theirs = generate(net, np.repeat(ref[None], 5, 0), np.repeat(ref_s[None], 5, 0), tgt, batch_size=3)
        assert ours.shape == (5, 32, 32, 3)
        assert np.abs(ours.astype(int) - theirs).max() <= 1
        assert ours.std() > 1  # not a constant picture


def test_contact_sheet_layout():
    obs = np.zeros((10, 32, 32, 3), np.uint8)
    fut = np.full((3, 20, 32, 32, 3), 128, np.uint8)
    sheet = contact_sheet(obs, fut, header=((obs[0], "reference"),))
    assert sheet.shape == (4 * 32 + 3 * 2, 8 * 32 + 7 * 2, 3)
    assert np.abs(sheet[32 + 2 + 24, 1].astype(int) - RED).max() < 5  # the left border of a future cell


# --- end to end -----------------------------------------------------------------------------------------

def test_synthesize_body_end_to_end(checkpoints, mocap_dir, tmp_path):
    out = tmp_path / "body.mp4"
    config = SynthesisConfig(samples=2, observed=6, horizon=5, seed=3)
    result = synthesize(motion_model=checkpoints["body"], frame_model=checkpoints["frames_body"],
                          input_path=mocap_dir / "cmu" / "131_02.bvh", reference=DEMO / "reference_body_128.png",
                          output=out, config=config)
    assert set(result.timings) == {"load", "sampling", "structures", "generation", "compose", "encoding", "total"}
    assert (result.samples, result.observed, result.horizon, result.domain) == (2, 6, 5, "body")
    assert any("resized to 64x64" in n for n in result.notes)
    frames, fps = read_video(out)
    assert frames.shape == (11, FRAME_SIZE, 2 * FRAME_SIZE + 2, 3) and fps == pytest.approx(25.0)
    assert_framed(frames, observed=6, cells=2, columns=2)
    structure, _ = read_video(result.structure_video)
    assert structure.shape == frames.shape
    sheet = read_image(result.sheet)
    assert sheet.shape == (3 * FRAME_SIZE + 2 * 2, 8 * FRAME_SIZE + 7 * 2, 3)
    # The reference structure came from the pose file: the first observed pose is aligned with it.
    st = result.structures
    ref_pose = R.load_reference_pose(DEMO / "reference_body_128.pose.npz")
    np.testing.assert_allclose(st.points[0], ref_pose.points * FRAME_SIZE / 128, atol=1e-4)


@pytest.mark.slow
def test_synthesize_face_end_to_end_and_same_seed_same_frames(face_dir, tmp_path):
    folder = tmp_path / "ckpt"
    folder.mkdir()
    motion, frames_model = train_face_motion_model(face_dir, folder), train_frame_model("face", folder)
    config = SynthesisConfig(samples=3, observed=4, horizon=4, seed=5)
    runs = []
    for name in ("a.mp4", "b.mp4"):
        result = synthesize(motion_model=motion, frame_model=frames_model, input_path=face_dir / "llv" / "dao.csv",
                              reference=DEMO / "reference_face.png", output=tmp_path / name, config=config)
        runs.append(read_video(result.video)[0])
    frames = runs[0]
    assert frames.shape == (8, 2 * FRAME_SIZE + 2, 2 * FRAME_SIZE + 2, 3)  # 3 cells in a 2 x 2 grid
    np.testing.assert_array_equal(runs[0], runs[1])
    assert_framed(frames, observed=4, cells=3, columns=2)
    grey = result.structures.images
    assert grey.shape == (1 + 4 + 3 * 4, FRAME_SIZE, FRAME_SIZE) and grey.max() > 100  # the face mesh is drawn
    # The reference structure is the pose file's face in its camera: it covers the reference picture's face.
    ref = R.load_reference(DEMO / "reference_face.png", size=FRAME_SIZE, domain="face")
    face_pixels = np.abs(ref.image.astype(int) - 255).sum(-1) > 60
    assert ((grey[0] > 20) & face_pixels).sum() > 0.7 * (grey[0] > 20).sum()


@pytest.mark.slow
def test_mesh_frames_of_the_same_futures(checkpoints, mocap_dir, tmp_path):
    result = synthesize(motion_model=checkpoints["body"], frame_model=checkpoints["frames_body"],
                          input_path=mocap_dir / "cmu" / "131_02.bvh", reference=DEMO / "reference_body_128.png",
                          output=tmp_path / "b.mp4", config=SynthesisConfig(samples=2, observed=4, horizon=3))
    mesh = render_mesh_frames(result.structures, size=64, fps=result.fps)
    assert mesh.observed.shape == (4, 64, 64, 3) and mesh.futures.shape == (2, 3, 64, 64, 3)
    body = np.abs(mesh.observed.astype(int) - 255).sum(-1) > 30
    assert 0.02 < body.mean() < 0.5  # a body, not an empty or filled frame


def _demo_module():
    sys.path.insert(0, str(REPO / "scripts"))
    try:
        import demo
    finally:
        sys.path.remove(str(REPO / "scripts"))
    return demo


def test_demo_names_the_missing_weight_file(tmp_path, capsys):
    demo = _demo_module()
    assert demo.main(["--out", str(tmp_path / "out"), "--weights", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "missing weight file" in err and f"{demo.BODY['frame_model']}.safetensors" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_demo_runs_from_the_repository_alone(checkpoints, face_dir, tmp_path, capsys):
    """The demo with tiny checkpoints in place of the shipped ones: every file is written."""
    demo = _demo_module()
    weights = tmp_path / "weights"
    weights.mkdir()
    from motion2video.generator.checkpoint import save_frame_model
    from motion2video.generator.mesh_warp import MeshWarpConfig, MeshWarpGenerator

    mesh = save_frame_model(MeshWarpGenerator(MeshWarpConfig(image_size=64)), tmp_path / "mesh.safetensors", step=0)
    face_mesh = save_frame_model(MeshWarpGenerator(MeshWarpConfig(domain="face", image_size=64, structure_channels=1)),
                                 tmp_path / "face-mesh.safetensors", step=0)
    names = {demo.BODY["motion_model"]: train_dlow_model(checkpoints["body"]), demo.BODY["frame_model"]: mesh,
             "frames-body-128": checkpoints["frames_body"],
             "mtvae-add-face": train_face_motion_model(face_dir, tmp_path),
             demo.FACE["frame_model"]: face_mesh,
             "behavior": train_behavior_model(checkpoints["body"].parent)}
    for name, path in names.items():
        (weights / f"{name}.safetensors").symlink_to(path)
    out = tmp_path / "out"
    # the real-photo video needs the shipped generators: tests/test_demo_photo.py runs it
    assert demo.main(["--out", str(out), "--weights", str(weights), "--samples", "1",
                      "--photos", str(tmp_path / "no-photos")]) == 0
    printed = capsys.readouterr().out
    assert "photo: skipped" in printed
    for name in ("futures_body.mp4", "futures_body-structure.mp4", "futures_body-sheet.png", "mesh_body.mp4",
                 "mesh_body-sheet.png", "futures_face.mp4", "futures_face-structure.mp4", "futures_face-sheet.png",
                 "transfer_body.mp4", "transfer_body-sheet.png", "transfer_body.npz"):
        assert (out / name).is_file() and str(out / name) in printed, name
    assert "transfer: cmu_jump.npz re-enacted" in printed  # the real CMU jump
    transfer, _ = read_video(out / "transfer_body.mp4")
    assert transfer.shape[:2] == (1 + 48, 256) and transfer.shape[2] >= 2 * 256  # the source beside the re-enactment
    kept = np.load(out / "transfer_body.npz")
    assert kept["source"].shape == (1 + 48, 17, 3) and kept["reenacted"].shape == (1, 1 + 48, 17, 3)
    mesh, _ = read_video(out / "mesh_body.mp4")
    assert mesh.shape == (16 + 48, 256, 256, 3)
    assert_framed(mesh, observed=16, cells=1, columns=1, size=256)


def test_streamed_composition_equals_the_whole_video():
    """compose_chunk over timeline chunks equals compose_video, and the sheet from picked frames equals
    contact_sheet (what synthesize streams)."""
    rng = np.random.default_rng(1)
    obs = rng.integers(0, 255, (5, 24, 24, 3), dtype=np.uint8)
    fut = rng.integers(0, 255, (3, 7, 24, 24, 3), dtype=np.uint8)
    whole = compose_video(obs, fut)
    steps = np.concatenate([np.repeat(obs[:, None], 3, axis=1), fut.transpose(1, 0, 2, 3, 4)])  # (12, K, ...)
    streamed = np.concatenate([compose_chunk(steps[s:s + 4], s, 5) for s in range(0, 12, 4)])
    np.testing.assert_array_equal(streamed, whole)
    header = ((obs[0], "reference"),)
    np.testing.assert_array_equal(contact_sheet_of(lambda t: obs[t], lambda k, t: fut[k, t], 5, 7, 3, header=header),
                                  contact_sheet(obs, fut, header=header))
