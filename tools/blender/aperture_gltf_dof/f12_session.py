# SPDX-License-Identifier: MIT OR Apache-2.0
"""F12 through the session the viewport shares (issue 63): with the ``aperture`` Python module,
F12 brings the loaded scene up to date (``viewport_sync.shared``: one export the first time,
then only the edits that changed, a re-export only for what edits cannot express) and renders
it in process, passes included, and denoised as the command line would (the same settings and
library, the same bits). A second F12 with nothing changed exports nothing.

The command-line path stays for what this one does not do yet: motion blur (the export then
carries the animation), a render border, and when the module is missing."""

from . import viewport_sync
from .scene_export import resolution


def usable(scene):
    """Whether F12 of ``scene`` can go through the shared session (else the CLI)."""
    r = scene.render
    s = scene.aperture
    return (s.f12_session and viewport_sync.available() and not r.use_motion_blur
            and not r.use_border)


def options(scene, pass_names, oidn=None):
    """``render`` options equal to the F12 command's, with its passes and its denoising
    (``oidn``: the library the command would get with ``--oidn``)."""
    opts = viewport_sync.render_options(scene, resolution(scene))
    opts["passes"] = list(pass_names) or "none"
    s = scene.aperture
    if s.denoise:
        opts.update(denoise=True, denoise_quality=s.denoise_quality.lower(),
                    denoise_prefilter=s.denoise_prefilter.lower())
        if oidn:
            opts["oidn"] = oidn
    return opts


def render(depsgraph, pass_names, cancelled, progress, oidn=None):
    """The F12 image of ``depsgraph``'s scene as EXR-style channels (``{"R": …, "Depth.Z": …}``,
    H×W float32 each, rows from the top), or None when ``cancelled()`` became true; and what
    the sync took (``[(path, name)]``). Denoised when the panel says so (``oidn``: the
    library)."""
    held = viewport_sync.existing(depsgraph)
    if held is not None:
        held.lock.acquire()  # the viewport lets go within its own update
    try:
        s = viewport_sync.shared(depsgraph)
        with s.lock:
            opts = options(depsgraph.scene, pass_names, oidn)
            if "noise_threshold" in opts:  # adaptive: one call (no progressive schedule)
                result = s.scene.render(**opts)
            else:
                run = s.scene.start(**opts)
                while not run.done:
                    if cancelled():
                        run.cancel()
                        return None, s.last_sync
                    run.step()
                    progress(run.samples / max(1, run.target))
                result = run.image()
            return channels(result), s.last_sync
    finally:
        if held is not None:
            held.lock.release()


def channels(result):
    """A ``RenderResult`` as the EXR reader's channel dict."""
    out = {c: result.image[..., i] for i, c in enumerate("RGBA")}
    for name, data in result.passes.items():
        for i, c in enumerate(result.channels[name]):
            out[f"{name}.{c}"] = data[..., i]
    return out
