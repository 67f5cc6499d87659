"""Offscreen video of an episode: MuJoCo's renderer, written as MP4 (imageio + ffmpeg) or an animated GIF.

Needs an OpenGL context: ``MUJOCO_GL=egl``, set before MuJoCo is first imported (importing
:mod:`sim` sets it when it is unset and there is no display: :mod:`sim.offscreen_gl`), works
on headless machines with a GPU driver or Mesa's EGL.  Without one, :class:`VideoRecorder`
records nothing and :meth:`VideoRecorder.close` returns a message saying why (without a
"no video" prefix: the caller says that once); the episode goes on.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from sim.offscreen_gl import gl_hint

__all__ = ["Caption", "VideoRecorder"]


class Caption:
    """Text drawn on a frame: a dark banner across the top, with an optional coloured patch
    (e.g. the task mode's colour) before the last part. Sized for a 640-pixel-wide frame."""

    def __init__(self, parts: list[str], patch_colour: str | None = None) -> None:
        self.parts, self.patch_colour = parts, patch_colour

    def draw(self, img: np.ndarray) -> np.ndarray:
        """``img`` (H, W, 3) uint8 with the caption drawn on a copy."""
        from PIL import Image, ImageDraw, ImageFont

        frame = Image.fromarray(np.ascontiguousarray(img))
        draw = ImageDraw.Draw(frame)
        size = max(12, frame.width // 36)
        font = ImageFont.load_default(size=size)
        pad = size // 2
        draw.rectangle([0, 0, frame.width, size + 2 * pad], fill=(20, 20, 20))
        x = pad
        for i, text in enumerate(self.parts):
            if self.patch_colour and i == len(self.parts) - 1:
                draw.rectangle([x, pad, x + size, pad + size], fill=self.patch_colour)
                x += size + pad // 2
            draw.text((x, pad), text, fill=(255, 255, 255), font=font)
            x += int(draw.textlength(text, font=font)) + 2 * pad
        return np.asarray(frame)


class VideoRecorder:
    """Captures frames every ``control_rate_hz / fps`` control steps from the camera ``camera``.

    ``path``: .mp4 (if ``imageio-ffmpeg`` is installed; otherwise the same name with
    .gif) or .gif.  GIF frames are kept palette-quantised in memory (≈ 300 kB each at
    640×480, the largest offscreen buffer the scene declares) and written on :meth:`close`.
    """

    def __init__(self, model: mujoco.MjModel, path: str | Path, fps: int = 25, control_rate_hz: float = 100.0,
                 width: int = 640, height: int = 480, camera: str = "side") -> None:
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
            self.message = f"offscreen OpenGL is not available ({type(exc).__name__}: {exc}); {gl_hint()}"
            return
        # Shadows, reflections and the skybox cost ~70 % of a frame under software OpenGL
        # (Mesa llvmpipe: 360 → 110 ms per 320×240 frame of the eating scene); the video
        # shows the motion, which needs none of them (nor multisampling: the scene's offsamples="0",
        # 38 → 12 ms of CPU per 640×480 frame).
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

    def wants(self, k: int) -> bool:
        """Whether control step ``k`` falls on a frame (so a caller builds a caption only then)."""
        return self._renderer is not None and k % self.every == 0

    def maybe_capture(self, data: mujoco.MjData, k: int, caption: Caption | None = None) -> None:
        """Render control step k if it falls on a frame, with ``caption`` drawn on it."""
        if not self.wants(k):
            return
        try:
            self._renderer.update_scene(data, camera=self.camera)
            img = self._renderer.render()
            if caption is not None:
                img = caption.draw(img)
        except Exception as exc:  # noqa: BLE001  (a GL failure mid-run must not stop the episode)
            self.message = f"rendering stopped at step {k}: {type(exc).__name__}: {exc}"
            self._renderer = None
            return
        if self._writer is not None:
            self._writer.append_data(img)
        else:
            from PIL import Image

            # the fast octree: about 100x cheaper than the default median cut on 640x480 frames, with no visible loss on
            # rendered scenes (few smooth colours)
            self._frames.append(Image.fromarray(np.ascontiguousarray(img)).quantize(
                colors=128, method=Image.Quantize.FASTOCTREE))

    def close(self) -> tuple[Path | None, str | None]:
        """Finish the file; returns (path or None, message or None)."""
        if self._renderer is not None:
            self._renderer.close()
        if self._writer is not None:
            self._writer.close()
            return self.path, self.message
        if not self._frames:
            return None, self.message or "no frame was rendered"
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._frames[0].save(self.path, save_all=True, append_images=self._frames[1:],
                             duration=round(1000 / self.fps), loop=0)
        self._frames = []
        return self.path, self.message
