"""Fast renderers: draw the classic-control scenes straight at low resolution from the physical state.

They draw the same geometry as gymnasium's pygame ``render()`` (same world-to-screen maps, same colours, already in
gray levels with the luminance weights of :class:`gymnasium.wrappers.GrayscaleObservation`) on a small supersampled
canvas with OpenCV, then area-average it to ``size x size``. No pygame, no 500x500 frame: about 40x faster than the
``gym`` renderer. ``tests/test_envs.py`` bounds the mean absolute gray-level difference to the ``gym`` pipeline.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

# Luminance weights of gymnasium's GrayscaleObservation (R, G, B).
_LUMA = (0.2125, 0.7154, 0.0721)


def gray(rgb: tuple[int, int, int]) -> int:
    """Gray level of an RGB colour under the luminance weights used by the ``gym`` pipeline."""
    return int(sum(w * c for w, c in zip(_LUMA, rgb, strict=True)))


class _Canvas:
    """A white supersampled canvas whose coordinates are those of the original screen (x right, y up)."""

    _SHIFT = 4  # fixed-point bits for sub-pixel polygon vertices

    def __init__(self, screen_w: float, screen_h: float, size: int, supersample: int) -> None:
        self.px = size * supersample
        self.sx, self.sy = self.px / screen_w, self.px / screen_h
        self.size = size
        self.img = np.full((self.px, self.px), 255, dtype=np.uint8)

    def _pts(self, pts: np.ndarray) -> np.ndarray:
        xy = np.stack([pts[:, 0] * self.sx, self.px - pts[:, 1] * self.sy], axis=1)  # flip y like the pygame code
        return np.round(xy * (1 << self._SHIFT)).astype(np.int32)

    def polygon(self, pts: np.ndarray, level: int) -> None:
        cv2.fillPoly(self.img, [self._pts(pts)], int(level), lineType=cv2.LINE_AA, shift=self._SHIFT)

    def polyline(self, pts: np.ndarray, level: int, thickness_px: float) -> None:
        """Draw a line ``thickness_px`` screen pixels wide; thinner than one canvas pixel, it is drawn one canvas
        pixel wide at a proportionally lighter level, so area-averaging keeps its ink."""
        width = thickness_px * self.sx
        level = round(255 - (255 - level) * min(1.0, width))
        t = max(1, round(width))
        cv2.polylines(self.img, [self._pts(pts)], False, int(level), t, lineType=cv2.LINE_AA, shift=self._SHIFT)

    def disc(self, centre: tuple[float, float], radius: float, level: int) -> None:
        c = self._pts(np.asarray([centre], dtype=np.float64))[0]
        r = round(radius * self.sx * (1 << self._SHIFT))
        cv2.circle(self.img, (int(c[0]), int(c[1])), r, int(level), -1, lineType=cv2.LINE_AA, shift=self._SHIFT)

    def frame(self) -> np.ndarray:
        return cv2.resize(self.img, (self.size, self.size), interpolation=cv2.INTER_AREA)


def _rect(length: float, half_width: float, angle: float, origin: tuple[float, float]) -> np.ndarray:
    """Corners of a bar from ``origin`` of given length and half-width, rotated by ``angle`` (radians)."""
    corners = np.array([[0.0, -half_width], [0.0, half_width], [length, half_width], [length, -half_width]])
    c, s = math.cos(angle), math.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    return corners @ rot.T + np.asarray(origin)


class AcrobotRenderer:
    """Acrobot-v1 as gymnasium draws it (500 px screen, bounds +-2.2 m), rendered to a ``size x size`` gray frame."""

    SCREEN = 500.0
    LINK = 1.0

    def __init__(self, size: int = 32, supersample: int = 4) -> None:
        self.size, self.supersample = size, supersample

    def __call__(self, state: np.ndarray) -> np.ndarray:
        """Render ``state`` = (theta1, theta2, dtheta1, dtheta2) to a (size, size) uint8 frame."""
        scale = self.SCREEN / (2 * (2 * self.LINK + 0.2))
        off = self.SCREEN / 2
        cv = _Canvas(self.SCREEN, self.SCREEN, self.size, self.supersample)
        cv.polyline(np.array([[-2.2 * scale + off, scale + off], [2.2 * scale + off, scale + off]]), 0, 1.0)
        t1, t2 = float(state[0]), float(state[1])
        p1 = (self.LINK * math.sin(t1) * scale + off, -self.LINK * math.cos(t1) * scale + off)
        for origin, theta in (((off, off), t1 - math.pi / 2), (p1, t1 + t2 - math.pi / 2)):
            cv.polygon(_rect(self.LINK * scale, 0.1 * scale, theta, origin), gray((0, 204, 204)))
            cv.disc(origin, int(0.1 * scale), gray((204, 204, 0)))
        return cv.frame()


class MountainCarRenderer:
    """MountainCar-v0 as gymnasium draws it (600x400 screen), squashed to a ``size x size`` gray frame."""

    W, H = 600.0, 400.0
    MIN_POS, MAX_POS, GOAL = -1.2, 0.6, 0.5

    def __init__(self, size: int = 32, supersample: int = 4) -> None:
        self.size, self.supersample = size, supersample

    @staticmethod
    def _height(x: np.ndarray | float) -> np.ndarray | float:
        return np.sin(3 * x) * 0.45 + 0.55

    def __call__(self, state: np.ndarray) -> np.ndarray:
        """Render ``state`` = (position, velocity) to a (size, size) uint8 frame."""
        scale = self.W / (self.MAX_POS - self.MIN_POS)
        cv = _Canvas(self.W, self.H, self.size, self.supersample)
        xs = np.linspace(self.MIN_POS, self.MAX_POS, 100)
        cv.polyline(np.stack([(xs - self.MIN_POS) * scale, self._height(xs) * scale], axis=1), 0, 1.0)
        pos = float(state[0])
        ang = math.cos(3 * pos)
        base = ((pos - self.MIN_POS) * scale, 10 + self._height(pos) * scale)
        c, s = math.cos(ang), math.sin(ang)
        rot = np.array([[c, -s], [s, c]])
        body = np.array([[-20.0, 0.0], [-20.0, 20.0], [20.0, 20.0], [20.0, 0.0]]) @ rot.T + base
        cv.polygon(body, 0)
        for wx in (10.0, -10.0):
            w = np.array([wx, 0.0]) @ rot.T + base
            cv.disc((int(w[0]), int(w[1])), int(20 / 2.5), gray((128, 128, 128)))
        fx = int((self.GOAL - self.MIN_POS) * scale)
        fy1 = int(self._height(self.GOAL) * scale)
        cv.polyline(np.array([[fx, fy1], [fx, fy1 + 50]], dtype=np.float64), 0, 1.0)
        cv.polygon(np.array([[fx, fy1 + 50], [fx, fy1 + 40], [fx + 25, fy1 + 45]], dtype=np.float64), gray((204, 204, 0)))
        return cv.frame()
