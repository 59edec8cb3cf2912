"""The local web app (``motion2video app``): animate a photo with a clip, a motion file or a video, and transfer a
behaviour, in the browser.

Gradio (the optional extra ``pip install -e ".[app]"``) draws the page; every button calls the Python API
(:mod:`motion2video.apps.api`: ``synthesize``, ``transfer``) and writes what it returns, nothing more. Bad input
shows the command line's one-line message (:class:`~motion2video.core.errors.InputError`) in the page, and the app
keeps serving. Work shows its stage (pose estimation, sampling, frames); Cancel stops it at the next step through
the API's ``progress`` callback, leaving no partial file. It binds 127.0.0.1 unless told otherwise: a local tool,
not a public service.
"""

from __future__ import annotations

import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import gradio as gr

from motion2video.apps import api
from motion2video.core.errors import InputError
from motion2video.formats.io import save_motion

DEMO_DIR = Path(__file__).resolve().parents[2] / "demo_inputs"  # beside the package in a clone
DEMO_PHOTOS = ("reference_body.png", "reference_body_128.png")
DEMO_CLIPS = ("walk_to_run.npz", "cmu_walk.npz", "cmu_jump.npz", "jump.npz", "wave.npz", "squat_punch_turn.npz")
MOTION_MODELS = ("mixture-periodic", "mtvae-add-dlow", "mtvae-add", "lcpvae", "mixer-cvae-dlow")
FRAME_MODELS = ("frames-body-mesh-256", "frames-body-mesh-128", "frames-body-128")
MAX_FUTURES = 6

# Where each stage's work starts in the whole bar (the frames take most of the time).
STAGE_START = {api.POSE_STAGE: 0.0, "loading": 0.1, "sampling": 0.15, "structures": 0.2, "frames": 0.25}


@dataclass(frozen=True)
class AppSettings:
    """Options of :func:`serve`.

    Attributes:
        host: the address to bind (127.0.0.1: this machine only).
        port: the port (0: a free one).
        motion_model, frame_model, samples, horizon: what the page starts with.
        max_video_seconds: longer uploaded videos are refused before their pose is estimated.
        work_dir: where each run's files go (None: a new temporary folder).
    """

    host: str = "127.0.0.1"
    port: int = 7860
    motion_model: str = "mixture-periodic"
    frame_model: str = "frames-body-mesh-256"
    samples: int = 3
    horizon: int = 48
    max_video_seconds: float = 30.0
    work_dir: Path | None = None


class Cancelled(Exception):
    """Raised from the API's progress callback after the page's Cancel button: the work stops at its next step."""


def _demo(name: str | None) -> Path | None:
    return DEMO_DIR / name if name else None


class App:
    """The page's handlers: each calls one API function and turns its result (or its InputError) into the page's
    outputs. One run at a time (Gradio's queue), so one cancel flag serves the page."""

    def __init__(self, settings: AppSettings):
        self.settings = settings
        self.work_dir = Path(settings.work_dir or tempfile.mkdtemp(prefix="motion2video-app-"))
        self.work_dir.mkdir(parents=True, exist_ok=True)
        self.cancel = threading.Event()

    def _run_dir(self) -> Path:
        return Path(tempfile.mkdtemp(prefix="run-", dir=self.work_dir))

    def _progress(self, bar: gr.Progress):
        """The API's ``progress(stage, fraction)`` -> Gradio's bar; raises :class:`Cancelled` once Cancel is pressed."""
        stages = list(STAGE_START)

        def report(stage: str, fraction: float) -> None:
            if self.cancel.is_set():
                raise Cancelled()
            start = STAGE_START.get(stage, 0.0)
            following = [STAGE_START[s] for s in stages if STAGE_START[s] > start]
            end = following[0] if following else 1.0
            bar(start + (end - start) * fraction, desc=stage)

        return report

    def stop(self) -> str:
        self.cancel.set()
        return "cancelled: the work stops at its next step"

    def animate(self, photo: str | None, demo_photo: str | None, clip: str | None, demo_clip: str | None,
                motion_model: str, frame_model: str, samples: float, horizon: float, seed: float, crop: bool,
                fit_view: bool, bar: gr.Progress = gr.Progress()):
        """The "Animate a photo" button: :func:`motion2video.apps.api.synthesize`."""
        self.cancel.clear()
        reference = photo or _demo(demo_photo)
        motion = clip or _demo(demo_clip)
        if reference is None or motion is None:
            return None, None, None, "motion2video synthesize: error: give a photo and a motion (or pick demo ones)"
        run = self._run_dir()
        try:
            result = api.synthesize(motion_model, frame_model, motion, reference, samples=int(samples),
                                    horizon=int(horizon), seed=int(seed), crop_person=bool(crop),
                                    fit_view=bool(fit_view), max_seconds=self.settings.max_video_seconds,
                                    output=run / "futures.mp4",
                                    progress=self._progress(bar))
        except InputError as err:
            run.rmdir()  # the API wrote nothing
            return None, None, None, f"motion2video synthesize: error: {err}"
        except Cancelled:
            run.rmdir()
            return None, None, None, "cancelled"
        futures = result.futures
        files = [result.video, result.structure_video]
        files += [save_motion(m, run / f"future_{k + 1}.npz") for k, m in enumerate(futures.motions)]
        files += futures.save_bvh(run / "bvh", stem="future")
        k = len(futures.futures)
        status = (f"{k} future{'s' if k > 1 else ''} of {futures.futures.shape[1]} frames after "
                  f"{len(futures.observed)} observed, {result.fps:g} fps, in {result.timings['total']:.1f} s")
        notes = "".join(f"\n\nnote: {n}" for n in result.notes)
        return str(result.video), str(result.structure_video), [str(f) for f in files], status + notes

    def transfer(self, target: str | None, demo_target: str | None, behavior: str | None, demo_behavior: str | None,
                 style: str, horizon: float, adapt: bool, bar: gr.Progress = gr.Progress()):
        """The "Transfer the behaviour" button: :func:`motion2video.apps.api.transfer`."""
        self.cancel.clear()
        target_clip = target or _demo(demo_target)
        source_clip = behavior or _demo(demo_behavior)
        if target_clip is None or source_clip is None:
            return None, None, "motion2video transfer: error: give a target and a behaviour clip (or pick demo ones)"
        run = self._run_dir()
        try:
            result = api.transfer("behavior", target_clip, behavior=source_clip, horizon=int(horizon),
                                  adapt_steps=None if adapt else 0, style=style,
                                  max_seconds=self.settings.max_video_seconds, output=run / "transfer.mp4",
                                  progress=self._progress(bar))
        except InputError as err:
            run.rmdir()  # the API wrote nothing
            return None, None, f"motion2video transfer: error: {err}"
        except Cancelled:
            run.rmdir()
            return None, None, "cancelled"
        files = [result.path, save_motion(result.motions[0], run / "reenacted.npz")]
        files += result.save_bvh(run / "bvh")
        status = f"the behaviour re-enacted for {result.reenacted.shape[1] - 1} frames, {result.fps:g} fps"
        return str(result.path), [str(f) for f in files], status


def build(settings: AppSettings = AppSettings()) -> tuple[gr.Blocks, App]:
    """The page: two tabs, "Animate a photo" and "Behaviour transfer"."""
    app = App(settings)
    clips = [c for c in DEMO_CLIPS if (DEMO_DIR / c).is_file()]
    photos = [p for p in DEMO_PHOTOS if (DEMO_DIR / p).is_file()]
    with gr.Blocks(title="motion2video", analytics_enabled=False) as page:
        gr.Markdown("# motion2video\nHuman motion in, video out: sampled futures of a motion, played by the person "
                    "in your photo.")
        with gr.Tab("Animate a photo"):
            with gr.Row():
                with gr.Column():
                    photo = gr.Image(type="filepath", sources=["upload"], label="Photo of a person",
                                     elem_id="photo", height=260)
                    demo_photo = gr.Dropdown(photos, value=photos[0] if photos else None, label="or a demo photo "
                                             "(used when no photo is uploaded)", elem_id="demo-photo")
                    crop = gr.Checkbox(True, label="cut the photo to the person")
                    fit_view = gr.Checkbox(False, label="zoom out when the motion leaves the picture")
                with gr.Column():
                    clip = gr.File(label="Motion: a mocap file (BVH, npz, DeepMimic, ...) or a video of a person",
                                   elem_id="clip", height=120)
                    demo_clip = gr.Dropdown(clips, value=clips[0] if clips else None,
                                            label="or a bundled clip (used when nothing is uploaded)",
                                            elem_id="demo-clip")
                    motion_model = gr.Dropdown(list(MOTION_MODELS), value=settings.motion_model, label="Motion model",
                                               allow_custom_value=True)
                    frame_model = gr.Dropdown(list(FRAME_MODELS), value=settings.frame_model, label="Frame model",
                                              allow_custom_value=True)
                    with gr.Row():
                        samples = gr.Slider(1, MAX_FUTURES, value=settings.samples, step=1, label="Futures")
                        horizon = gr.Slider(4, 96, value=settings.horizon, step=1, label="Future frames")
                        seed = gr.Number(0, precision=0, label="Seed")
            with gr.Row():
                go = gr.Button("Animate", variant="primary", elem_id="animate")
                stop = gr.Button("Cancel", elem_id="cancel")
            status = gr.Markdown(elem_id="status")
            with gr.Row():
                video = gr.Video(label="Futures (observed frames green, futures red)", autoplay=True, loop=True,
                                 elem_id="futures")
                structure = gr.Video(label="Structure", autoplay=True, loop=True, elem_id="structure")
            downloads = gr.File(label="Downloads: mp4, npz and BVH per future", file_count="multiple",
                                elem_id="downloads")
            run = go.click(app.animate, [photo, demo_photo, clip, demo_clip, motion_model, frame_model, samples,
                                         horizon, seed, crop, fit_view], [video, structure, downloads, status])
            stop.click(app.stop, None, status, cancels=[run])
        with gr.Tab("Behaviour transfer"):
            gr.Markdown("The behaviour of one clip (a jump, a kick) re-enacted from another clip's posture by the "
                        "behaviour model.")
            with gr.Row():
                with gr.Column():
                    target = gr.File(label="Target: whose posture re-enacts it", elem_id="target", height=120)
                    demo_target = gr.Dropdown(clips, value="cmu_walk.npz" if "cmu_walk.npz" in clips else None,
                                              label="or a bundled target")
                with gr.Column():
                    behavior = gr.File(label="Behaviour: the clip whose behaviour is transferred", elem_id="behavior",
                                       height=120)
                    demo_behavior = gr.Dropdown(clips, value="cmu_jump.npz" if "cmu_jump.npz" in clips else None,
                                                label="or a bundled behaviour")
                with gr.Column():
                    style = gr.Radio(["mesh", "skeleton"], value="mesh", label="Drawn as", elem_id="transfer-style")
                    t_horizon = gr.Slider(4, 96, value=settings.horizon, step=1, label="Generated frames")
                    adapt = gr.Checkbox(True, label="fit the decoder to the behaviour first (about 6 s)",
                                        elem_id="transfer-adapt")
            with gr.Row():
                t_go = gr.Button("Transfer", variant="primary", elem_id="transfer")
                t_stop = gr.Button("Cancel")
            t_status = gr.Markdown(elem_id="transfer-status")
            t_video = gr.Video(label="Behaviour (left) and its re-enactment (right)", autoplay=True, loop=True,
                               elem_id="transfer-video")
            t_downloads = gr.File(label="Downloads: mp4, npz and BVH", file_count="multiple",
                                  elem_id="transfer-downloads")
            t_run = t_go.click(app.transfer, [target, demo_target, behavior, demo_behavior, style, t_horizon, adapt],
                               [t_video, t_downloads, t_status])
            t_stop.click(app.stop, None, t_status, cancels=[t_run])
    return page, app


def serve(settings: AppSettings = AppSettings()) -> None:
    """Build the page and serve it until Ctrl-C, printing its address first."""
    page, app = build(settings)
    # No web fonts: the page loads offline, as the rest of the project runs.
    theme = gr.themes.Default(font=["ui-sans-serif", "system-ui", "sans-serif"], font_mono=["ui-monospace", "monospace"])
    page.queue(default_concurrency_limit=1)
    _, url, _ = page.launch(server_name=settings.host, server_port=settings.port or None, quiet=True,
                            prevent_thread_lock=True, show_error=True, allowed_paths=[str(app.work_dir)], theme=theme,
                            ssr_mode=False, footer_links=[])
    print(f"motion2video app: serving on {url.rstrip('/')} (Ctrl-C stops it)", flush=True)
    try:
        while True:  # Ctrl-C or SIGTERM ends it as it ends every command (cli.main)
            time.sleep(0.5)
    finally:
        page.close()
