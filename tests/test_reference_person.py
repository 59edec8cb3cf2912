"""A body reference picture must show a person: a picture with nobody in it is refused by every shipped body frame
model (one line naming the file, exit 2, nothing written), and a person cut by the picture's edge gets one note
and a picture extended to hold their pose."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.generator.checkpoint import load_frame_model
from motion2video.models.checkpoint import shipped_names
from motion2video.stages.reference import cut_edges, load_reference, pose_margins


def body_frame_models() -> list[str]:
    """Every shipped frame model that makes body frames, from the model registry."""
    names = [n for n in shipped_names() if n.startswith("frames-")]
    return [n for n in names if load_frame_model(n).config.domain == "body"]


BODY_FRAME_MODELS = body_frame_models()


def test_the_registry_ships_body_frame_models_of_every_kind():
    kinds = {getattr(load_frame_model(n), "kind", "analogy") for n in BODY_FRAME_MODELS}
    assert {"frames-body-128", "frames-body-mesh-256"} <= set(BODY_FRAME_MODELS) and "mesh" in kinds


@pytest.mark.parametrize("frame_model", BODY_FRAME_MODELS)
def test_a_plain_colour_reference_is_refused_naming_the_file(frame_model, mocap_dir, tmp_path, capsys):
    wall = tmp_path / "plain_wall.png"
    assert cv2.imwrite(str(wall), np.full((300, 240, 3), (90, 160, 200), np.uint8))
    out = tmp_path / "out" / "wall.mp4"
    code = main(["synthesize", "--motion-model", "mixture-periodic", "--frame-model", frame_model,
                 str(mocap_dir / "cmu" / "131_02.bvh"), "--reference", str(wall), "--samples", "1", "--horizon", "4",
                 "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.count("\n") == 0 and "error:" in err and str(wall) in err and "no person found" in err, err
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == [wall]  # nothing written, not even a partial file


def test_transfer_refuses_a_plain_colour_reference_too(mocap_dir, tmp_path, capsys):
    wall = tmp_path / "plain_wall.png"
    assert cv2.imwrite(str(wall), np.full((200, 200, 3), 240, np.uint8))
    out = tmp_path / "out" / "transfer.mp4"
    code = main(["transfer", "--model", "behavior", "--behavior", str(mocap_dir / "cmu" / "131_02.bvh"), "--target",
                 str(mocap_dir / "cmu" / "08_01.bvh"), "--style", "frames", "--frame-model", "frames-body-mesh-256",
                 "--reference", str(wall), "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0 and str(wall) in err and "no person found" in err, err
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == [wall]


def test_a_person_cut_by_the_bottom_edge_gets_a_note_and_an_extended_picture(photos_dir, tmp_path):
    photo = cv2.imread(str(photos_dir / "woman_blue_tracksuit.jpg"))  # 1080 x 1920, head to feet
    whole = tmp_path / "whole.jpg"
    assert cv2.imwrite(str(whole), photo)
    ref = load_reference(whole, size=128, domain="body")
    assert not any("cut by the picture's edge" in n for n in ref.notes), ref.notes
    assert ref.picture is not None and ref.picture[:, 64].min() > 0.5  # only the side pads are not the file's

    cut = tmp_path / "cut_at_the_shins.jpg"
    assert cv2.imwrite(str(cut), photo[:1440])  # the feet (about y 1700-1860) are outside this crop
    ref = load_reference(cut, size=128, domain="body")
    notes = [n for n in ref.notes if "cut by the picture's edge" in n]
    assert len(notes) == 1 and "\n" not in notes[0], ref.notes
    assert "cut_at_the_shins.jpg" in notes[0] and "feet past the bottom edge" in notes[0]
    assert "extended" in notes[0] and "px bottom" in notes[0]
    # the ankles lay below the crop: the picture is extended downwards, those rows are marked as not the file's,
    # and every joint now lies inside the reference
    assert np.all((ref.pose.points >= 0) & (ref.pose.points < 128))
    ankles = ref.pose.points[[3, 6]]
    assert ankles[:, 1].min() > 100
    col = ref.picture[:, int(round(ankles[:, 0].mean()))]
    assert col[int(ankles[:, 1].max())] < 0.5 and col[30] > 0.5


def test_synthesize_prints_the_cut_note_once_on_stderr(photos_dir, mocap_dir, tmp_path, capsys):
    photo = cv2.imread(str(photos_dir / "woman_blue_tracksuit.jpg"))
    cut = tmp_path / "cut_at_the_shins.jpg"
    assert cv2.imwrite(str(cut), photo[:1440])
    out = tmp_path / "cut.mp4"
    assert main(["synthesize", "--motion-model", "mixture-periodic", "--frame-model", "frames-body-128",
                 str(mocap_dir / "cmu" / "131_02.bvh"), "--reference", str(cut), "--samples", "1", "--horizon", "4",
                 "-o", str(out)]) == 0
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if "cut by the picture's edge" in line]
    assert len(lines) == 1 and lines[0].startswith("motion2video synthesize: note:"), captured.err
    assert "cut by the picture's edge" not in captured.out and out.is_file()


def test_cut_edges_and_pose_margins_name_what_runs_past_which_edge():
    from motion2video.pose.blazepose import LANDMARK_NAMES

    xy = np.tile([50.0, 50.0], (33, 1))
    xy[LANDMARK_NAMES.index("left_ankle")] = [40.0, 130.0]
    xy[LANDMARK_NAMES.index("right_heel")] = [60.0, 125.0]
    xy[LANDMARK_NAMES.index("left_wrist")] = [-3.0, 60.0]
    assert cut_edges(xy, width=100, height=120) == {"left": ("hands",), "bottom": ("feet",)}
    assert cut_edges(xy, width=100, height=200) == {"left": ("hands",)}
    points = np.tile([50.0, 20.0], (17, 1))
    points[3] = [45.0, 110.0]  # the right ankle 10 px below a 100 px picture; the pose is 90 px tall
    assert pose_margins(points, width=100, height=100) == (0, 0, 0, int(np.ceil(10 + 0.06 * 90)))
    assert pose_margins(points, width=100, height=120) == (0, 0, 0, 0)


def test_a_picture_of_nobody_is_refused_as_a_body_and_as_a_face_reference(tmp_path):
    """Without a pose file the person is found in the picture: a body by BlazePose, a face by the face mesh."""
    wall = tmp_path / "face_wall.png"
    assert cv2.imwrite(str(wall), np.full((64, 64, 3), 128, np.uint8))
    with pytest.raises(InputError, match="no face found in the reference image") as err:
        load_reference(wall, size=64, domain="face")
    assert str(wall) in str(err.value)
    with pytest.raises(InputError, match="no person found") as err:
        load_reference(wall, size=64, domain="body")
    assert str(wall) in str(err.value)
