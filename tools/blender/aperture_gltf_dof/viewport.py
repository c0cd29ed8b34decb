# SPDX-License-Identifier: MIT OR Apache-2.0
"""The engine's viewport (issue 63): ``view_update`` syncs the session (viewport_sync) and
restarts its worker, ``view_draw`` draws the latest film and never waits. Without the
``aperture`` Python module both do nothing (F12 keeps the command-line path). The drawing is
untested headless (bpy as a module has no window)."""

import numpy as np

from . import viewport_sync


def view_matrix(region_data):
    """The viewport's own view (not through a camera) as a glTF camera node matrix: Blender's
    camera-to-world turned to +Y up (C @ M, the camera correction included)."""
    c = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]], float)
    return c @ np.array(region_data.view_matrix.inverted())


class ViewportMixin:
    """``view_update``/``view_draw`` of the aperture engine."""

    _aperture_session = None

    def view_update(self, context, depsgraph):
        if not viewport_sync.available():
            return
        # The session F12 shares: while F12 renders with it, the viewport tries again later
        # rather than wait (Blender's main thread never blocks on a render).
        held = viewport_sync.existing(depsgraph)
        if held is not None and not held.lock.acquire(blocking=False):
            self.tag_update()
            return
        try:
            s = self._aperture_session = viewport_sync.synced(depsgraph)
            camera = depsgraph.scene.camera
            rd = context.region_data
            if rd is not None and rd.view_perspective != "CAMERA" and camera:
                s.scene.set_camera(camera.data.name, view_matrix(rd), lens=context.space_data.lens,
                                   sensor_width=72.0, use_dof=False)
                s.forget_camera(camera)
            denoise, start = viewport_sync.viewport_denoise(depsgraph.scene)
            s.start(width=context.region.width, height=context.region.height,
                    denoise_start=start, **denoise)
            if s.notice:
                self.report({"WARNING"}, f"aperture: {s.notice}")
        except Exception as e:  # never raised into Blender: the header shows it
            self.report({"ERROR"}, f"aperture: {e}")
        finally:
            if held is not None:
                held.lock.release()

    def view_draw(self, context, depsgraph):
        s = self._aperture_session
        film = s.film() if s is not None else None
        if film is not None:
            import gpu
            from gpu_extras.presets import draw_texture_2d

            h, w = film.shape[:2]
            data = gpu.types.Buffer("FLOAT", w * h * 4, np.ascontiguousarray(film[::-1]).ravel())
            texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)
            gpu.state.blend_set("ALPHA_PREMULT")
            self.bind_display_space_shader(depsgraph.scene)
            draw_texture_2d(texture, (0, 0), context.region.width, context.region.height)
            self.unbind_display_space_shader()
            gpu.state.blend_set("NONE")
        if s is not None and s.worker is not None and s.worker.wait(0) is False:
            self.tag_redraw()  # more samples are coming

    def __del__(self):
        # The session is shared with F12 (viewport_sync.shared): it stays loaded; a new file
        # or disabling the add-on frees it (viewport_sync.free_shared).
        try:
            if self._aperture_session is not None:
                self._aperture_session.stop()
        except ReferenceError:
            pass
