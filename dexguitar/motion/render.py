"""Pictures of a motion: a PNG strip of evenly spaced frames, or an .mp4 video (with `imageio-ffmpeg`).

Rendering uses MuJoCo's own OpenGL renderer on the render-only stage of the hand's scene (`world.stage`), with a
free camera looking at the hand (or the stage's "front" camera). Headless machines need an offscreen GL: the
context comes from `glcheck` (OSMesa or EGL, whichever really works; not `mujoco.Renderer`, which fixes
its GL backend when `mujoco` is first imported). PNGs are written by a small zlib encoder, so no imaging library
is needed.
"""
from __future__ import annotations

import struct
import zlib
from pathlib import Path

import mujoco
import numpy as np

from dexguitar.motion import glcheck
from dexguitar.motion.format import Motion
from dexguitar.world import scene as S
from dexguitar.world import stage
from dexguitar.world.kinematics import hand_kinematics


# ----------------------------------------------------------------------------------------------------- PNG

def write_png(path: str | Path, rgb: np.ndarray) -> Path:
    """Write an (H, W, 3) uint8 image as an 8-bit RGB PNG."""
    rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) image, got {rgb.shape}")
    h, w, _ = rgb.shape
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rgb.reshape(h, w * 3)], axis=1)   # filter byte 0 per row

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6)) + chunk(b"IEND", b""))
    path = Path(path)
    path.write_bytes(png)
    return path


def png_size(path: str | Path) -> tuple[int, int]:
    """(width, height) from a PNG header; raises ValueError if the file is not a PNG."""
    head = Path(path).read_bytes()[:24]
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{path}: not a PNG file")
    return struct.unpack(">II", head[16:24])


# ----------------------------------------------------------------------------------------------------- GL

FONT_SCALES = (50, 100, 150, 200, 250, 300)      # MuJoCo's font sizes, percent
CAPTION_FONT_AT_720 = 150


def font_scale(height: int) -> mujoco.mjtFontScale:
    """The font size for a frame `height`: 150 % at 720 lines, so a caption takes the same share of any frame."""
    want = height / 720 * CAPTION_FONT_AT_720
    return mujoco.mjtFontScale(min(FONT_SCALES, key=lambda s: abs(s - want)))


class Offscreen:
    """MuJoCo's renderer on an offscreen GL context: pixels of a model's data seen from a camera, with an optional
    caption. Shared by the motion strips and the performance videos. `fast`: no shadows (software GL spends most
    of a frame on them). Raises `glcheck.NoGL` when this machine has no offscreen OpenGL."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, fast: bool = False):
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        self.model, self.width, self.height = model, width, height
        self._ctx = glcheck.gl_context(width, height)
        self._con = mujoco.MjrContext(model, font_scale(height))
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        if fast:
            self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self._opt = mujoco.MjvOption()
        self._pert = mujoco.MjvPerturb()

    def render(self, data: mujoco.MjData, camera: mujoco.MjvCamera, caption: str | None = None) -> np.ndarray:
        """(H, W, 3) uint8 image of `data` after its kinematics (the hands' state is their qpos), with `caption`
        (lines of text) in the top left corner."""
        m = self.model
        self._ctx.make_current()
        mujoco.mj_kinematics(m, data)
        mujoco.mj_camlight(m, data)                # fixed cameras and lights follow from the kinematics
        mujoco.mjv_updateScene(m, data, self._opt, self._pert, camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene)
        rect = mujoco.MjrRect(0, 0, self.width, self.height)
        mujoco.mjr_render(rect, self._scene, self._con)
        if caption:
            mujoco.mjr_overlay(mujoco.mjtFont.mjFONT_NORMAL, mujoco.mjtGridPos.mjGRID_TOPLEFT, rect, caption, "",
                               self._con)
        rgb = np.empty((self.height, self.width, 3), np.uint8)
        mujoco.mjr_readPixels(rgb, None, rect, self._con)
        return np.flipud(rgb)

    def close(self):
        if self._ctx is not None:
            self._con.free()
            self._ctx.free()
            self._ctx = None


def fixed_camera(model: mujoco.MjModel, name: str) -> mujoco.MjvCamera:
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
    if cid < 0:
        raise ValueError(f"no camera {name!r} in the scene")
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
    camera.fixedcamid = cid
    return camera


class MotionRenderer:
    """Renders frames of one motion's scene. `camera`: "hand" (a free camera looking at the motion's mean wrist
    position) or the name of a scene camera ("front")."""

    def __init__(self, motion: Motion, width: int = 480, height: int = 360, camera: str = "hand",
                 mirror: bool = False):
        self.motion = motion
        self.model = stage.stage_model(motion.hand, mirror=mirror)
        m = self.model
        self.width, self.height = width, height
        self.data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, self.data, 0)
        kin = hand_kinematics(motion.hand, mirror)
        self.qpos = kin.model_qpos(motion.hand, motion.qpos)
        self.qadr = np.asarray(S.hand_index(m, motion.hand).qpos)
        self._screen = Offscreen(m, width, height)
        self.camera = mujoco.MjvCamera()
        if camera == "hand":
            wrist = S.hand_index(m, motion.hand).key_bodies[0]
            pts = []
            for q in self.qpos[:: max(1, len(self.qpos) // 50)]:
                self.data.qpos[self.qadr] = q
                mujoco.mj_kinematics(m, self.data)
                pts.append(self.data.xpos[wrist].copy())
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            self.camera.lookat[:] = np.mean(pts, axis=0)
            self.camera.distance = 0.5
            # Seen from in front of the fretboard (guitar +z), a little from the treble side and the body:
            # direction lookat -> camera in the guitar frame, turned into the free camera's azimuth / elevation.
            _, rot = S.guitar_pose(m)
            sign = -1.0 if mirror else 1.0
            view = rot @ np.array([0.35 * sign, -0.25, 1.0])
            fwd = -view / np.linalg.norm(view)
            self.camera.azimuth = float(np.degrees(np.arctan2(fwd[1], fwd[0])))
            self.camera.elevation = float(np.degrees(np.arcsin(fwd[2])))
        else:
            self.camera = fixed_camera(m, camera)

    def frame(self, t: int) -> np.ndarray:
        """(H, W, 3) uint8 image of motion frame t."""
        self.data.qpos[self.qadr] = self.qpos[t]
        return self._screen.render(self.data, self.camera)

    def close(self):
        self._screen.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def strip_frames(n_frames: int, count: int) -> np.ndarray:
    """`count` evenly spaced frame indices from first to last."""
    return np.unique(np.round(np.linspace(0, n_frames - 1, max(1, min(count, n_frames)))).astype(int))


def render_motion(motion: Motion, out: str | Path, *, frames: int = 8, width: int = 480, height: int = 360,
                  camera: str = "hand", mirror: bool = False, video_fps: float = 30.0) -> Path:
    """Write `out`: a .png strip of `frames` evenly spaced frames side by side (frames * width x height), or an
    .mp4 of the whole motion at `video_fps` (needs the optional `imageio-ffmpeg`). Returns the path."""
    out = Path(out)
    if out.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg
        except ImportError:
            raise RuntimeError(f"{out}: writing .mp4 needs the optional package imageio-ffmpeg "
                               f"(pip install imageio-ffmpeg); render a .png strip instead") from None
        idx = np.round(np.arange(0, motion.seconds + 1e-9, 1.0 / video_fps) * motion.fps).astype(int)
        with MotionRenderer(motion, width, height, camera, mirror) as r:
            writer = imageio_ffmpeg.write_frames(str(out), (width, height), fps=video_fps, macro_block_size=1)
            writer.send(None)
            for t in idx:
                writer.send(np.ascontiguousarray(r.frame(int(t))))
            writer.close()
        return out
    if out.suffix.lower() != ".png":
        raise ValueError(f"{out}: expected a .png (frame strip) or .mp4 (video) path")
    with MotionRenderer(motion, width, height, camera, mirror) as r:
        images = [r.frame(int(t)) for t in strip_frames(motion.n_frames, frames)]
    return write_png(out, np.concatenate(images, axis=1))
