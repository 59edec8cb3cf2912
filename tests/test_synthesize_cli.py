"""`motion2video synthesize` end to end on tiny checkpoints trained here, and its bad-input errors: one
line, exit code 2, and none of the three outputs written."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.apps.synthesize import output_paths
from motion2video.formats.video import read_image, read_video
from tests.test_pipeline import (DEMO, FRAME_SIZE, assert_framed, train_body_motion_model, train_face_motion_model,
                                 train_frame_model)


@pytest.fixture(scope="module")
def ckpt(tmp_path_factory, mocap_dir, face_dir) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("synthesize_ckpt")
    return {"body": train_body_motion_model(mocap_dir, folder), "face": train_face_motion_model(face_dir, folder),
            "frames_body": train_frame_model("body", folder), "frames_face": train_frame_model("face", folder)}


@pytest.fixture
def body_args(ckpt, mocap_dir) -> list[str]:
    return ["synthesize", "--motion-model", str(ckpt["body"]), "--frame-model", str(ckpt["frames_body"]),
            str(mocap_dir / "cmu" / "131_02.bvh"), "--observed", "6", "--horizon", "4"]


def test_body_videos_sheet_and_same_seed_same_frames(body_args, tmp_path, capsys):
    runs = {}
    for name, seed in (("a", "7"), ("b", "7"), ("c", "8")):
        out = tmp_path / f"{name}.mp4"
        assert main(body_args + ["--reference", str(DEMO / "reference_body_128.png"), "--samples", "3",
                                 "--seed", seed, "-o", str(out)]) == 0
        runs[name] = [read_video(p)[0] for p in output_paths(out)[:2]]
        assert read_image(output_paths(out)[2]).shape == (4 * FRAME_SIZE + 3 * 2, 8 * FRAME_SIZE + 7 * 2, 3)
    captured = capsys.readouterr()
    assert "wrote" in captured.out and "a-structure.mp4" in captured.out and "a-sheet.png" in captured.out
    assert "note: reference image is 128x128: resized to 64x64" in captured.err
    video, structure = runs["a"]
    assert video.shape == (10, 2 * FRAME_SIZE + 2, 2 * FRAME_SIZE + 2, 3)  # 6 + 4 frames, 3 cells in 2 x 2
    assert structure.shape == video.shape
    assert_framed(video, observed=6, cells=3, columns=2)
    assert_framed(structure, observed=6, cells=3, columns=2)
    np.testing.assert_array_equal(runs["a"][0], runs["b"][0])
    np.testing.assert_array_equal(runs["a"][1], runs["b"][1])
    # Another seed: the same observed structure (up to H.264, whose frames depend on their neighbours), and the
    # same first future frame (every future continues the observed motion: stages.sampling.continue_observed),
    # then other futures.
    diff = np.abs(runs["a"][1].astype(float) - runs["c"][1]).mean(axis=(1, 2, 3))  # (T,)
    assert diff[:7].max() < 0.5 and diff[7:].min() > 4 * diff[:7].max() + 0.1, diff


def test_rigid_bones_changes_only_the_futures(body_args, tmp_path):
    """--rigid-bones reaches the sampling stage: the observed frames are drawn the same, the futures not."""
    videos = {}
    for name, extra in (("raw", []), ("rigid", ["--rigid-bones"])):
        out = tmp_path / f"{name}.mp4"
        assert main(body_args + ["--reference", str(DEMO / "reference_body_128.png"), "--samples", "2",
                                 "-o", str(out)] + extra) == 0
        videos[name] = read_video(output_paths(out)[1])[0].astype(float)  # the structure video
    diff = np.abs(videos["raw"] - videos["rigid"]).mean(axis=(1, 2, 3))  # (T,)
    assert diff[:6].max() < 0.5 and diff[6:].max() > 1.0, diff


def test_converted_references_get_a_note(body_args, tmp_path, capsys):
    ref = cv2.imread(str(DEMO / "reference_body_128.png"))
    grey = tmp_path / "grey.png"
    rgba = tmp_path / "rgba.png"
    cv2.imwrite(str(grey), cv2.cvtColor(ref, cv2.COLOR_BGR2GRAY))
    cv2.imwrite(str(rgba), cv2.resize(np.dstack([ref, np.full(ref.shape[:2], 255, np.uint8)]), (64, 64)))
    for image, note in ((grey, "grey-scale image converted to RGB"), (rgba, "RGBA image composited over a white")):
        out = tmp_path / f"{image.stem}.mp4"
        assert main(body_args + ["--reference", str(image), "--samples", "1", "-o", str(out)]) == 0
        err = capsys.readouterr().err
        assert note in err and "no reference pose file" in err  # no .pose.npz beside these copies
        assert all(p.is_file() for p in output_paths(out))


def _fails(args: list[str], capsys, out: Path) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "motion2video synthesize: error:" in err, err
    for path in output_paths(out):
        assert not path.exists(), path
    assert not list(out.parent.glob(".*partial*")) and not list(out.parent.glob("*.tmp*"))
    return err


def test_bad_input_one_line_exit_2_and_no_partial_files(ckpt, body_args, mocap_dir, face_dir, tmp_path, capsys):
    out = tmp_path / "x.mp4"
    ref = ["--reference", str(DEMO / "reference_body_128.png")]
    k = ["--samples", "2"]
    o = ["-o", str(out)]
    (tmp_path / "broken.png").write_bytes(b"\x89PNG not really")
    assert "no such reference image" in _fails(body_args + ["--reference", str(tmp_path / "nope.png")] + k + o,
                                               capsys, out)
    assert "cannot decode the reference image" in _fails(body_args + ["--reference", str(tmp_path / "broken.png")]
                                                         + k + o, capsys, out)
    assert "--samples must be >= 1" in _fails(body_args + ref + ["--samples", "0"] + o, capsys, out)
    assert "samples must be in 1..64" in _fails(body_args + ref + ["--samples", "65"] + o, capsys, out)
    short = str(mocap_dir / "mass" / "mass_run.bvh")  # 14 frames at 25 fps
    err = _fails(["synthesize", "--motion-model", str(ckpt["body"]), "--frame-model", str(ckpt["frames_body"]), short]
                 + ref + k + o, capsys, out)
    assert "shorter than the observed" in err and "mass_run.bvh" in err
    # A face frame model with a body motion model, and the reverse.
    err = _fails(["synthesize", "--motion-model", str(ckpt["body"]), "--frame-model", str(ckpt["frames_face"]),
                  str(mocap_dir / "cmu" / "131_02.bvh"), "--reference", str(DEMO / "reference_face.png")] + k + o,
                 capsys, out)
    assert "makes face frames" in err and "body motion" in err
    err = _fails(["synthesize", "--motion-model", str(ckpt["face"]), "--frame-model", str(ckpt["frames_body"]),
                  str(face_dir / "llv" / "dao.csv")] + ref + k + o, capsys, out)
    assert "makes body frames" in err and "face motion" in err
    # Body motion given to a face model, face motion given to a body model.
    err = _fails(["synthesize", "--motion-model", str(ckpt["face"]), "--frame-model", str(ckpt["frames_face"]),
                  str(mocap_dir / "cmu" / "131_02.bvh"), "--reference", str(DEMO / "reference_face.png")] + k + o,
                 capsys, out)
    assert "131_02.bvh" in err and "face model" in err
    err = _fails(body_args[:5] + [str(DEMO / "smile.npz")] + ref + k + o, capsys, out)
    assert "smile.npz" in err and "body model" in err
    # A reference pose of the wrong kind, a wrong output extension, an output folder under a file, a missing model.
    err = _fails(body_args + ref + ["--reference-pose", str(DEMO / "reference_face.pose.npz")] + k + o, capsys, out)
    assert "face pose, but the frame model makes body frames" in err
    assert "must be an .mp4" in _fails(body_args + ref + k + ["-o", str(tmp_path / "x.gif")], capsys,
                                       tmp_path / "x.gif")
    (tmp_path / "afile").write_text("x")
    assert "afile is a file" in _fails(body_args + ref + k + ["-o", str(tmp_path / "afile" / "no" / "x.mp4")],
                                       capsys, tmp_path / "afile" / "no" / "x.mp4")
    err = _fails(["synthesize", "--motion-model", str(tmp_path / "none.safetensors"), "--frame-model",
                  str(ckpt["frames_body"]), str(DEMO / "walk_to_run.npz")] + ref + k + o, capsys, out)
    assert "no such checkpoint" in err
    assert "--observed must be >= 2" in _fails(body_args[:6] + ["--observed", "1"] + ref + k + o, capsys, out)


def _warp_frame_model(folder: Path) -> Path:
    """A 64 px warp generator trained for 2 steps on the toy set by the real training loop."""
    from motion2video.generator.data import toy_sequences
    from motion2video.generator.training import TrainFramesConfig, train_frames
    from motion2video.generator.warp import WarpGeneratorConfig

    seqs = toy_sequences("body", num_sequences=2, frames_per_sequence=3, image_size=FRAME_SIZE)
    result = train_frames(seqs, output=folder / "frames_warp.safetensors",
                          config=TrainFramesConfig(steps=2, batch_size=2, warmup_steps=1, checkpoint_every=2,
                                                   log_every=1, model_kind="warp"),
                          model_config=WarpGeneratorConfig(image_size=FRAME_SIZE), progress=False)
    return Path(result.path)


def test_warp_model_keeps_a_full_resolution_background(ckpt, mocap_dir, tmp_path, capsys):
    warp = _warp_frame_model(tmp_path)
    out = tmp_path / "w.mp4"
    args = ["synthesize", "--motion-model", str(ckpt["body"]), "--frame-model", str(warp),
            str(mocap_dir / "cmu" / "131_02.bvh"), "--observed", "6", "--horizon", "4",
            "--reference", str(DEMO / "reference_body_128.png"), "--samples", "1", "-o", str(out)]
    assert main(args + ["--size", "128"]) == 0
    assert "resized" not in capsys.readouterr().err  # the 128 px reference is used as it is
    video = read_video(out)[0]
    assert video.shape[1:] == (128, 128, 3)  # one cell of 128 px (the frame drawn inside it)
    sheet = read_image(output_paths(out)[2])
    assert sheet.shape[0] > 2 * 128
    # An analogy generator cannot make another size.
    out2 = tmp_path / "a.mp4"
    err = _fails(args[:4] + [str(ckpt["frames_body"])] + args[5:-1] + [str(out2), "--size", "128"], capsys, out2)
    assert "needs a body warp or mesh frame model" in err


@pytest.mark.parametrize("points, message", [
    (lambda p: p + [0.0, 500.0], "joint(s) outside the 64x64 image"),
    (lambda p: np.full_like(p, 30.0), "no visible person"),
])
def test_bad_reference_poses_are_refused(body_args, tmp_path, capsys, points, message):
    from motion2video.stages.reference import ReferencePose, load_reference_pose, save_reference_pose

    good = load_reference_pose(DEMO / "reference_body_128.pose.npz")
    bad = tmp_path / "bad.pose.npz"
    save_reference_pose(bad, ReferencePose("body", good.width, good.height, points=points(good.points)))
    out = tmp_path / "x.mp4"
    err = _fails(body_args + ["--reference", str(DEMO / "reference_body_128.png"), "--reference-pose", str(bad),
                              "--samples", "1", "-o", str(out)], capsys, out)
    assert message in err and "bad.pose.npz" in err


def test_a_reference_image_without_a_person_is_refused(body_args, tmp_path, capsys):
    """A uniform image with a valid pose file beside it: one line naming the image, exit 2, nothing written."""
    import shutil

    from motion2video.formats.video import read_image, write_image

    image = read_image(DEMO / "reference_body_128.png")
    blank = tmp_path / "blank.png"
    write_image(blank, np.broadcast_to(image[0, 0], image.shape).copy())
    shutil.copy(DEMO / "reference_body_128.pose.npz", tmp_path / "blank.pose.npz")
    out = tmp_path / "x.mp4"
    err = _fails(body_args + ["--reference", str(blank), "--samples", "1", "-o", str(out)], capsys, out)
    assert "blank.png" in err and "no visible person" in err


def test_a_blank_reference_without_a_pose_file_is_refused_naming_it(ckpt, mocap_dir, tmp_path, capsys):
    """The shipped warp generator given a uniform picture and no pose file: the person is looked for in the picture
    and none is found: one line naming the picture, exit 2, nothing written."""
    from motion2video.formats.video import read_image, write_image

    image = read_image(DEMO / "reference_body_128.png")
    blank = tmp_path / "blank.png"
    write_image(blank, np.broadcast_to(image[0, 0], image.shape).copy())
    out = tmp_path / "x.mp4"
    err = _fails(["synthesize", "--motion-model", str(ckpt["body"]), "--frame-model", "frames-body-128",
                  str(mocap_dir / "cmu" / "131_02.bvh"), "--observed", "6", "--horizon", "4", "--reference", str(blank),
                  "--samples", "1", "-o", str(out)], capsys, out)
    assert f"{blank}: no person found in the reference image" in err
