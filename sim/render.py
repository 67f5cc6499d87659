"""Offscreen video of an episode: MuJoCo's renderer, written as MP4 (imageio + ffmpeg) or an animated GIF.

Needs an OpenGL context: ``MUJOCO_GL=egl``, set before MuJoCo is first imported (the
``mpcshare`` command line sets it when it is unset and there is no display), works
on headless machines with a GPU driver or Mesa's EGL.  Without one, :class:`VideoRecorder`
records nothing and :meth:`VideoRecorder.close` returns a message saying so; the episode goes on.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

__all__ = ["VideoRecorder"]


class VideoRecorder:
    """Captures frames every ``control_rate_hz / fps`` control steps from the camera ``camera``.

    ``path``: .mp4 (if ``imageio-ffmpeg`` is installed; otherwise the same name with
    .gif) or .gif.  GIF frames are kept palette-quantised in memory (≈ 75 kB each at
    320×240) and written on :meth:`close`.
    """

    def __init__(self, model: mujoco.MjModel, path: str | Path, fps: int = 25, control_rate_hz: float = 100.0,
                 width: int = 320, height: int = 240, camera: str = "side") -> None:
        self.path = Path(path)
        if self.path.suffix.lower() not in (".mp4", ".gif"):
            raise ValueError(f"video path must end in .mp4 or .gif, got {self.path.name!r}")
        self.every = max(round(control_rate_hz / fps), 1)
        self.fps, self.camera = fps, camera
        self.message: str | None = None
        self._frames: list = []
        self._writer = None
        try:
            self._renderer = mujoco.Renderer(model, height, width)
        except Exception as exc:  # noqa: BLE001  (no OpenGL context, whatever the backend raises: say so)
            self._renderer = None
            self.message = (f"no video: offscreen OpenGL is not available ({type(exc).__name__}: {exc}); "
                            "set MUJOCO_GL=egl (or osmesa) to render")
            return
        # Shadows, reflections and the skybox cost ~70 % of a frame under software OpenGL
        # (Mesa llvmpipe: 360 → 110 ms per 320×240 frame of the eating scene); the video
        # shows the motion, which needs none of them.
        for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION,
                     mujoco.mjtRndFlag.mjRND_SKYBOX):
            self._renderer.scene.flags[flag] = False
        if self.path.suffix.lower() == ".mp4":
            try:
                import imageio.v2 as imageio
                import imageio_ffmpeg  # noqa: F401  (the mp4 writer's backend)

                self._writer = imageio.get_writer(str(self.path), fps=fps, macro_block_size=8)
            except ImportError:
                self.path = self.path.with_suffix(".gif")

    def maybe_capture(self, data: mujoco.MjData, k: int) -> None:
        """Render control step k if it falls on a frame."""
        if self._renderer is None or k % self.every:
            return
        try:
            self._renderer.update_scene(data, camera=self.camera)
            img = self._renderer.render()
        except Exception as exc:  # noqa: BLE001  (a GL failure mid-run must not stop the episode)
            self.message = f"rendering stopped at step {k}: {type(exc).__name__}: {exc}"
            self._renderer = None
            return
        if self._writer is not None:
            self._writer.append_data(img)
        else:
            from PIL import Image

            self._frames.append(Image.fromarray(np.ascontiguousarray(img)).quantize(colors=128))

    def close(self) -> tuple[Path | None, str | None]:
        """Finish the file; returns (path or None, message or None)."""
        if self._renderer is not None:
            self._renderer.close()
        if self._writer is not None:
            self._writer.close()
            return self.path, self.message
        if not self._frames:
            return None, self.message or "no video: no frame was rendered"
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._frames[0].save(self.path, save_all=True, append_images=self._frames[1:],
                             duration=round(1000 / self.fps), loop=0)
        self._frames = []
        return self.path, self.message
