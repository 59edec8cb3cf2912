"""The samplers trained on the corpus joined with Bandai-Namco's files (``*-bandai``): each says it is for
non-commercial use where a user picks it and when it is loaded, and forecasts real clips of performers it never
saw: a held-out CMU subject's walk and a held-out Bandai-Namco performer's (group 1B) walk, read from their BVH files.
"""

from __future__ import annotations

import numpy as np
import pytest

from motion2video.apps.sample import load_clip_for
from motion2video.cli import main
from motion2video.data.licences import shipped_licences
from motion2video.models import checkpoint as C
from motion2video.stages.sampling import forecast

MODELS = ("mixture-periodic-bandai", "mtvae-add-dlow-bandai", "mixer-cvae-dlow-bandai", "mtvae-add-bandai",
          "mixer-cvae-bandai")
NOTE = "was trained on non-commercial data (CC BY-NC 4.0): its outputs are for non-commercial use only"
# CMU subject 2 is one of the corpus's test subjects; Bandai group 1B one of the subject split's test performers.
CLIPS = ("mocap/cmu/02_01.bvh", "bandai/bvh/dataset-1_walk-back_active_001.bvh.xz")


@pytest.mark.parametrize("name", MODELS)
def test_the_model_records_non_commercial_data_and_the_held_out_performers(name):
    meta = C.read_meta(C.resolve_checkpoint(name))
    licences = meta.data_summary["licences"]
    assert licences["non_commercial"] and licences["licences"]["CC BY-NC 4.0"] > 500
    assert shipped_licences()[name]["non_commercial"]
    train = set(meta.split.train) | set(meta.split.val)
    assert any(n.startswith("bandai/") for n in train)
    assert not train & set(CLIPS) and "cmu/02_01.bvh" not in train


def test_loading_prints_the_non_commercial_note_once_and_samples_finite_futures(shared_dir, capsys):
    capsys.readouterr()
    bundle = C.load_model("mixture-periodic-bandai")
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"motion2video: note: mixture-periodic-bandai {NOTE}"]
    for rel in CLIPS:
        clip = load_clip_for(bundle, shared_dir / "data" / rel)
        assert clip.ndim == 3 and clip.shape[1:] == (17, 3) and len(clip) >= 64
        fc = forecast(bundle, clip, num_samples=50, start=8, seed=0)
        assert fc.futures.shape == (50, 48, 17, 3) and np.isfinite(fc.futures).all()
        # the futures start where the observed frames end (within one step of the last observed pose)
        last = fc.observed[-1]
        step = np.linalg.norm(fc.futures[:, 0] - last, axis=-1).mean(-1)
        assert step.max() < 0.3, rel
        # distinct futures: the mixture draws from three samplers
        assert np.linalg.norm(fc.futures[:, -1] - fc.futures[:1, -1], axis=-1).mean(-1)[1:].min() > 1e-3


def test_help_lists_the_models_with_their_non_commercial_licence(capsys):
    with pytest.raises(SystemExit):
        main(["sample", "--help"])
    text = capsys.readouterr().out
    licences = text.split("data licences of the shipped models")[1]
    for name in MODELS:
        line = next(x for x in licences.splitlines() if x.split()[:1] == [name])
        assert "NON-COMMERCIAL data (CC BY-NC 4.0)" in line, line
    listed = text.split("shipped motion models")[1].split("data licences of the shipped models")[0]
    assert all(f"  {name} " in listed for name in MODELS)
