"""The public API of ``import motion2video``: the names, their homes, a cheap package import, and a tiny motion
through save -> load -> render (render_motion and the streaming iter_frames) -> write_video -> read back."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import motion2video
from motion2video import InputError, Motion, iter_frames, load_motion, render_motion, save_motion, write_video
from motion2video.core.errors import InputError as CoreInputError
from motion2video.core.motion import Motion as CoreMotion
from motion2video.formats.io import load_motion as io_load_motion
from motion2video.formats.video import read_video
from motion2video.testing.golden import synthetic_walk

REPO = Path(__file__).resolve().parents[1]


def test_public_names_are_the_defining_modules_objects():
    # one name per thing: the package's names are the very objects of the modules that define them
    assert Motion is CoreMotion and InputError is CoreInputError and load_motion is io_load_motion
    for name in ("load_motion", "save_motion", "render_motion", "iter_frames", "write_video", "Motion",
                 "InputError"):
        assert name in motion2video.__all__ and name in dir(motion2video)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        motion2video.nope  # noqa: B018


def test_package_import_loads_no_heavy_module():
    code = ("import sys, motion2video; heavy = [m for m in ('torch', 'cv2', 'av', 'renderers', 'pyrender') "
            "if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=REPO, env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"})
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_round_trip_and_render_two_frames(tmp_path):
    walk = synthetic_walk(2, fps=25.0)  # (2, 17, 3)
    path = save_motion(walk, tmp_path / "walk.npz")
    motion = load_motion(path)
    assert isinstance(motion, Motion) and motion.fps == 25.0 and motion.skeleton == "h36m-17"
    np.testing.assert_array_equal(motion.joints, walk.joints)

    frames = render_motion(motion, style="skeleton", size=64)
    assert frames.shape == (2, 64, 64, 3) and frames.dtype == np.uint8 and frames.any()
    streamed = np.concatenate(list(iter_frames(motion, style="skeleton", size=64)))
    np.testing.assert_array_equal(streamed, frames)

    video = write_video(tmp_path / "walk.mp4", iter_frames(motion, style="skeleton", size=64), motion.fps)
    back, fps = read_video(video)
    assert back.shape == (2, 64, 64, 3) and fps == pytest.approx(25.0)
    error = np.abs(back.astype(np.int16) - frames).mean(axis=(1, 2, 3))  # (2,) per frame
    swapped = np.abs(back.astype(np.int16) - frames[::-1]).mean(axis=(1, 2, 3))
    assert np.all(error < 4.0) and np.all(error < swapped)  # H.264 at crf 18: each frame is its own drawn frame

    with pytest.raises(InputError, match="needs a face motion"):
        render_motion(motion, style="face", size=64)


# --- the pipeline: load_model, sample, synthesize, transfer, analogy, estimate_pose ---------------------------

CLIP = REPO / "demo_inputs" / "walk_to_run.npz"  # a real CMU walk turning into a run, 25 fps
REFERENCE = REPO / "demo_inputs" / "reference_body_128.png"  # with its pose file beside it


def test_pipeline_names_are_exported():
    from motion2video.apps import api
    from motion2video.testing.golden import assert_frames_match as golden_assert

    for name in ("load_model", "sample", "synthesize", "transfer", "analogy", "estimate_pose", "Futures",
                 "Synthesis", "Transfer", "Analogy", "Pose"):
        assert getattr(motion2video, name) is getattr(api, name) and name in motion2video.__all__
    from motion2video.testing import assert_frames_match

    assert assert_frames_match is golden_assert


def test_load_model_tells_motion_models_frame_models_and_baselines_apart():
    from motion2video.generator.checkpoint import LoadedFrameModel
    from motion2video.models.checkpoint import ModelBundle

    motion, frames, baseline = (motion2video.load_model(n) for n in ("mtvae-add", "frames-body-128", "zero-velocity"))
    assert isinstance(motion, ModelBundle) and motion.data_config.layout == "body3d"
    assert isinstance(frames, LoadedFrameModel) and frames.config.domain == "body"
    assert isinstance(baseline, ModelBundle) and baseline.kind == "baseline"
    with pytest.raises(InputError, match="no such checkpoint file or shipped model name"):
        motion2video.load_model("no-such-model")


def test_sample_gives_futures_as_arrays_motions_and_files(tmp_path):
    model = motion2video.load_model("mtvae-add")
    futures = motion2video.sample(model, CLIP, samples=2, observed=8, horizon=6, seed=1, size=64,
                                  output=tmp_path / "futures.mp4")
    assert futures.observed.shape == (8, 17, 3) and futures.futures.shape == (2, 6, 17, 3)
    assert futures.layout == "body3d" and futures.fps == 25.0 and futures.model == "mtvae-add"
    assert not np.allclose(futures.futures[0], futures.futures[1])  # two different futures
    again = motion2video.sample("mtvae-add", CLIP, samples=2, observed=8, horizon=6, seed=1)
    np.testing.assert_array_equal(again.futures, futures.futures)  # the same seed, the same futures
    assert again.video is None and again.path is None

    motions = futures.motions
    assert len(motions) == 2 and all(isinstance(m, Motion) and m.num_frames == 14 for m in motions)
    np.testing.assert_array_equal(motions[1].joints[:8], futures.observed)
    np.testing.assert_array_equal(motions[1].joints[8:], futures.futures[1])

    assert futures.video.shape[0] == 14 and futures.video.dtype == np.uint8
    back, fps = read_video(futures.path)
    assert back.shape == futures.video.shape and fps == pytest.approx(25.0)
    assert np.abs(back.astype(np.int16) - futures.video).mean() < 4.0  # the written video is the returned one

    with np.load(futures.save_npz(tmp_path / "futures.npz")) as npz:
        np.testing.assert_array_equal(npz["futures"], futures.futures)
    bvh = futures.save_bvh(tmp_path / "bvh")
    assert [p.name for p in bvh] == ["sample_1.bvh", "sample_2.bvh"]
    read = load_motion(bvh[0])
    assert read.skeleton == "h36m-17" and read.num_frames == 14

    with pytest.raises(InputError, match="walk_to_run.npz"):
        motion2video.sample(model, CLIP, samples=1, start=10_000)
    with pytest.raises(InputError, match="frame generator"):
        motion2video.sample("frames-body-128", CLIP)


def test_synthesize_returns_the_frames_it_writes(tmp_path):
    stages = []
    result = motion2video.synthesize("mtvae-add", "frames-body-128", CLIP, REFERENCE, samples=2, observed=8,
                                     horizon=6, output=tmp_path / "person.mp4",
                                     progress=lambda stage, fraction: stages.append((stage, fraction)))
    assert result.frames.shape == (2, 14, 128, 128, 3) and result.frames.dtype == np.uint8
    assert result.structure.shape == result.frames.shape and result.structure.any()
    np.testing.assert_array_equal(result.frames[0, :8], result.frames[1, :8])  # the observed frames are shared
    assert not np.array_equal(result.frames[0, 8:], result.frames[1, 8:])  # the futures are not
    assert result.futures.futures.shape == (2, 6, 17, 3) and result.fps == 25.0
    assert [s for s, _ in stages[:4]] == ["loading", "sampling", "structures", "frames"]
    assert stages[-1] == ("frames", 1.0)

    assert result.video.is_file() and result.structure_video.is_file() and result.sheet.is_file()
    grid, fps = read_video(result.video)
    assert grid.shape[0] == 14 and fps == pytest.approx(25.0)
    # the grid's cells (128 px, a 2 px gap) hold the frames: compared below the label, inside the border, after H.264
    for k, x in enumerate((0, 130)):
        cell = grid[:, 30:120, x + 10:x + 118].astype(np.int16)  # (T, 90, 108, 3)
        own = np.abs(cell - result.frames[k, :, 30:120, 10:118]).mean()
        other = np.abs(cell[8:] - result.frames[1 - k, 8:, 30:120, 10:118]).mean()  # another future's frames
        assert own < 3.0 and np.abs(cell[8:] - result.frames[k, 8:, 30:120, 10:118]).mean() < other, (k, own, other)

    unwritten = motion2video.synthesize("mtvae-add", "frames-body-128", CLIP, REFERENCE, samples=2, observed=8,
                                        horizon=6)
    assert unwritten.video is None and unwritten.sheet is None
    np.testing.assert_array_equal(unwritten.frames, result.frames)  # the same seed, the same frames


def test_synthesize_cancelled_by_its_progress_leaves_no_file(tmp_path):
    class Cancelled(Exception):
        pass

    def cancel(stage, fraction):
        if stage == "frames" and fraction > 0:
            raise Cancelled()

    with pytest.raises(Cancelled):
        motion2video.synthesize("mtvae-add", "frames-body-128", CLIP, REFERENCE, samples=1, observed=8,
                                horizon=30, output=tmp_path / "person.mp4", progress=cancel)
    assert list(tmp_path.iterdir()) == []


def test_synthesize_refuses_a_photo_with_nobody_when_cutting_to_the_person(tmp_path):
    import cv2

    blank = tmp_path / "wall.png"
    cv2.imwrite(str(blank), np.full((200, 160, 3), 180, np.uint8))
    with pytest.raises(InputError, match=r"wall\.png.*no person found|no person found.*wall\.png"):
        motion2video.synthesize("mtvae-add", "frames-body-128", CLIP, blank, samples=1, crop_person=True,
                                output=tmp_path / "out.mp4")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wall.png"]


def test_transfer_reenacts_a_behaviour_and_samples_the_flow(tmp_path):
    walk, jump = REPO / "demo_inputs" / "cmu_walk.npz", REPO / "demo_inputs" / "cmu_jump.npz"
    result = motion2video.transfer("behavior", walk, behavior=jump, horizon=8, adapt_steps=0, style="skeleton",
                                   size=64, output=tmp_path / "transfer.mp4")
    assert result.source.shape == (9, 17, 3) and result.reenacted.shape == (1, 9, 17, 3)
    assert result.style == "skeleton" and result.video.shape[0] == 9 and result.path.is_file()
    assert isinstance(result.motions[0], Motion) and result.motions[0].num_frames == 9
    assert [p.name for p in result.save_bvh(tmp_path / "bvh")] == ["reenacted_1.bvh"]

    flow = motion2video.transfer("behavior", walk, samples=2, horizon=8, seed=3)
    assert flow.source is None and flow.reenacted.shape == (2, 9, 17, 3) and flow.video is None
    np.testing.assert_allclose(flow.reenacted[0, 0], flow.reenacted[1, 0])  # both start at the target's posture
    with pytest.raises(InputError, match="either a behaviour clip or a number of flow samples"):
        motion2video.transfer("behavior", walk)
    with pytest.raises(InputError, match="behaviour"):
        motion2video.transfer("mtvae-add", walk, samples=1)


def test_analogy_applies_a_transition_to_another_clip():
    walk, jump = REPO / "demo_inputs" / "cmu_walk.npz", REPO / "demo_inputs" / "cmu_jump.npz"
    result = motion2video.analogy("mtvae-add", walk, walk, jump, observed=8, horizon=8, render=True, size=64)
    assert result.ab.shape == (16, 17, 3) and result.cd.shape == (16, 17, 3) and result.consecutive
    assert result.observed == 8 and result.z.ndim == 1 and result.video.shape[0] == 16
    assert result.motion.num_frames == 16 and result.motion.skeleton == "h36m-17"


def test_estimate_pose_of_a_photo_and_the_length_limit_of_a_video(tmp_path, shared_dir):
    pose = motion2video.estimate_pose(shared_dir / "data" / "photos" / "skier.jpg")
    assert pose.points2d.shape == (1, 17, 2) and pose.joints3d.shape == (1, 17, 3) and pose.people >= 1
    assert pose.fps is None and 0 <= pose.points2d[..., 0].min() and pose.points2d[..., 0].max() <= pose.width
    saved = pose.save(tmp_path / "skier.pose.npz")
    from motion2video.stages.reference import load_reference_pose

    np.testing.assert_allclose(load_reference_pose(saved).points, pose.points2d[0], atol=1e-4)
    with pytest.raises(InputError, match="a photo's pose is one frame"):
        pose.motion  # noqa: B018
    with pytest.raises(InputError, match=r"dancer\.avi.*at most 0.5 s|at most 0.5 s.*dancer\.avi"):
        motion2video.estimate_pose(shared_dir / "data" / "video" / "dancer.avi", max_seconds=0.5)
    with pytest.raises(InputError, match="no such file"):
        motion2video.estimate_pose(tmp_path / "missing.jpg")
