"""Animations of runs: the arm, its end-effector trace, the goal and the manipulability ellipse.

A planar arm is drawn in its plane; a spatial arm in three orthogonal projections of the base
frame (top x-y, front x-z, side y-z), each with the projection of the translational
manipulability ellipsoid ``{J_v qd : ||qd|| <= 1}`` (the ellipse of ``P J_v`` for the projection
``P``). The ellipse at the end effector is ``{x : x^T (J J^T)^-1 x <= 1}``, the set of end-effector
velocities reachable with ``||qd|| <= 1`` (mathematics.md eq. 7): its semi-axes are the square roots of the
eigenvalues of ``J J^T`` along its eigenvectors. It is drawn ``scale`` times its size in m/s, so that
it reads at the arm's scale; the factor is stated on screen.

Frames are drawn by blitting on the Agg canvas (the static background is rendered once) and
written as GIF (Pillow) and MP4 (ffmpeg from the imageio-ffmpeg wheel). Frame ``i`` shows state
``k_i`` and lasts ``(k_{i+1} - k_i) dt / speedup``; the stride is chosen so that the frame time is
a whole number of GIF centiseconds and the frame rate is at most ``max_fps``. The last frame is
held ``hold`` seconds.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon
from PIL import Image

from ..core.arm import Matrix, PlanarArm
from ..core.scenario import Scenario
from ..sim.loop import Run
from .style import CONTROLLER_STYLE, RC, figure_canvas
from .views import Views

CIRCLE = np.stack((np.cos(np.linspace(0, 2 * np.pi, 73)), np.sin(np.linspace(0, 2 * np.pi, 73))))


def ellipse_points(J: Matrix, p: np.ndarray, scale: float) -> Matrix:
    """Boundary of the scaled manipulability ellipse at ``p``: ``p + scale U sqrt(L) c`` (73 x 2)."""
    lam, U = np.linalg.eigh(J @ J.T)
    return np.asarray(p[:, None] + scale * (U * np.sqrt(np.maximum(lam, 0.0))) @ CIRCLE).T


GIF_LONGEST_MS = 655_350
"""A GIF frame's longest duration in ms: its delay is a 16-bit count of hundredths of a second."""


def frame_schedule(steps: int, dt: float, speedup: float, max_fps: float) -> tuple[list[int], int]:
    """State indices shown, and the stride: the smallest with a whole-centisecond frame time
    and at most ``max_fps`` frames per second."""
    if dt / speedup * 1000.0 > GIF_LONGEST_MS:
        raise ValueError(
            f"one step would show for {dt / speedup:.3g} s, longer than a GIF frame can last "
            f"({GIF_LONGEST_MS / 1000:g} s): use a larger speed-up"
        )
    stride = 1
    while True:
        frame_ms = stride * dt / speedup * 1000.0
        if 1000.0 / frame_ms <= max_fps + 1e-9 and abs(frame_ms / 10 - round(frame_ms / 10)) < 1e-6:
            break
        stride += 1
        if stride > 10_000:
            raise ValueError("no frame stride fits dt and speedup; try another speedup")
    indices = list(range(0, steps + 1, stride))
    if indices[-1] != steps:
        indices.append(steps)
    return indices, stride


class Animator:
    """Draws ``runs`` side by side, frame by frame (a frame is a state index of the longest run)."""

    def __init__(
        self, runs: Sequence[Run], *, speedup: float = 1.0, max_fps: float = 20.0, hold: float = 1.0
    ) -> None:
        if speedup <= 0 or max_fps <= 0:
            raise ValueError("speedup and max_fps must be > 0")
        self.runs = list(runs)
        sc = self.runs[0].scenario
        self.dt = sc.motion.dt
        self.speedup, self.hold = speedup, hold
        self.steps = max(run.steps for run in self.runs)
        self.indices, self.stride = frame_schedule(self.steps, self.dt, speedup, max_fps)
        self.views = Views(sc)
        biggest = max(
            float(np.sqrt(np.linalg.eigvalsh(J @ J.T)[-1]))
            for run in self.runs
            for q in run.q[:: max(1, run.steps // 50) if sc.robot.dim == 3 else 1]
            for J in (self.views.jacobian(q),)
        )
        self.box = self.views.limits(self.runs)
        size = 0.5 * float((self.box[:, 1] - self.box[:, 0]).max()) / 1.08
        self.scale = 0.3 * size / biggest if biggest > 0 else 1.0
        self._frames: list[np.ndarray] | None = None
        with matplotlib.rc_context(RC):
            self._build(sc)

    def _build(self, sc: Scenario) -> None:
        """Figure, static background and the animated artists (inside the shared style)."""
        views = self.views
        cols = len(views.projections)
        rows = len(self.runs) if cols > 1 else 1
        per_row = len(self.runs) if cols == 1 else cols
        self.fig, self.canvas = figure_canvas(width=3.3 * per_row, height=3.4 * rows)
        grid = self.fig.subplots(rows, per_row, squeeze=False)
        self._artists: list[dict[str, Any]] = []
        goal = np.asarray(sc.motion.goal[: sc.robot.dim])
        for index, run in enumerate(self.runs):
            for v, P in enumerate(views.projections):
                ax = grid[index, v] if cols > 1 else grid[0, index]
                self._artists.append(self._panel(ax, sc, run, v, P, goal))
        self.canvas.draw()
        self._background = self.canvas.copy_from_bbox(self.fig.bbox)

    def _panel(
        self,
        ax: Any,
        sc: Scenario,
        run: Run,
        v: int,
        P: Matrix,
        goal: np.ndarray,
    ) -> dict[str, Any]:
        """One view of one run: the static background and its animated artists."""
        views = self.views
        style = CONTROLLER_STYLE.get(run.controller.name, {"color": "#0072B2"})
        arm = sc.robot
        if isinstance(arm, PlanarArm):  # the reachable annulus is drawn in the plane only
            ax.add_patch(Circle((0, 0), arm.reach, color="grey", alpha=0.08, linewidth=0))
            if arm.inner_reach > 0:
                ax.add_patch(Circle((0, 0), arm.inner_reach, color="white", linewidth=0))
        ax.plot(*(P @ goal), marker="*", color="black", markersize=10, linestyle="none")
        obstacles = views.draw_obstacles(ax, P, animated=views.moving)
        ax.set_xlim(*(P @ self.box)[0])
        ax.set_ylim(*(P @ self.box)[1])
        ax.set_aspect("equal")
        ax.set_xlabel(f"{views.axes[v][0]} (m)")
        ax.set_ylabel(f"{views.axes[v][1]} (m)")
        name = views.names[v]
        ax.set_title(
            f"{sc.name}: {run.controller.name}" + (f", {name}" if name else ""),
            fontsize=8 if name else None,
        )
        trace = Line2D([], [], color=style["color"], linewidth=1.0, animated=True)
        links = Line2D(
            [],
            [],
            color="black",
            linewidth=2.0,
            marker="o",
            markersize=3.5,
            markerfacecolor="white",
            animated=True,
        )
        ellipse = Polygon(
            np.zeros((2, 2)),
            closed=True,
            facecolor=style["color"],
            alpha=0.25,
            edgecolor=style["color"],
            animated=True,
        )
        text = ax.text(
            0.02,
            0.98,
            "",
            transform=ax.transAxes,
            va="top",
            fontsize=7,
            animated=True,
            family="monospace",
        )
        ax.add_line(trace)
        ax.add_patch(ellipse)
        ax.add_line(links)
        ax.text(
            0.02,
            0.02,
            f"ellipse x{self.scale:.2g} (m/s per rad/s)",
            transform=ax.transAxes,
            fontsize=6,
            color="grey",
        )
        return {
            "ax": ax,
            "trace": trace,
            "links": links,
            "ellipse": ellipse,
            "text": text if v == 0 else None,
            "run": run,
            "P": P,
            "obstacles": obstacles if views.moving else [],
        }

    @property
    def durations_ms(self) -> list[int]:
        """How long each frame is shown (ms): true to ``dt`` at the speed-up; the last is held."""
        out = []
        for a, b in itertools.pairwise(self.indices):
            out.append(round((b - a) * self.dt / self.speedup * 1000))
        out.append(round(self.hold * 1000))
        return out

    def draw(self, frame: int) -> np.ndarray:
        """Render frame ``frame`` and return it as an RGB array (height x width x 3)."""
        k = self.indices[frame]
        self.canvas.restore_region(self._background)
        views = self.views
        unit = "m, rad" if run_is_pose(self.runs[0]) else "m"
        for art in self._artists:
            run, P = art["run"], art["P"]
            kk = min(k, run.steps)
            q = run.q[kk]
            points = views.joints(q) @ P.T
            path = views.position(run)
            art["links"].set_data(points[:, 0], points[:, 1])
            trace = path[: kk + 1] @ P.T
            art["trace"].set_data(trace[:, 0], trace[:, 1])
            J = P @ views.jacobian(q)
            art["ellipse"].set_xy(ellipse_points(J, P @ path[kk], self.scale))
            names = ["trace", "ellipse", "links"]
            if art["text"] is not None:
                clear = run.clearance[kk] if run.clearance.size else np.inf
                art["text"].set_text(
                    f"t = {run.t[kk]:5.2f} s\nm = {run.m[kk]:.4f}\n"
                    f"|e| = {run.error_norm[kk]:.3f} {unit}"
                    + (f"\nclearance = {clear:.3f} m" if np.isfinite(clear) else "")
                )
                names.append("text")
            ax = art["ax"]
            if art["obstacles"]:
                views.move_obstacles(art["obstacles"], P, float(run.t[kk]))
                for patch in art["obstacles"]:
                    ax.draw_artist(patch)
            for name in names:
                ax.draw_artist(art[name])
        self.canvas.blit(self.fig.bbox)
        buffer = np.asarray(self.canvas.buffer_rgba())
        return buffer[:, :, :3].copy()

    def ellipse_at(self, frame: int, run_index: int = 0) -> Matrix:
        """The ellipse polygon as drawn in ``frame`` for run ``run_index`` (for checks)."""
        self.draw(frame)
        first = next(a for a in self._artists if a["run"] is self.runs[run_index])
        return np.asarray(first["ellipse"].get_xy())

    def frames(self) -> list[np.ndarray]:
        """Every frame's pixels, drawn once and kept: the GIF and the MP4 share them."""
        if self._frames is None:
            self._frames = [self.draw(i) for i in range(len(self.indices))]
        return self._frames

    def save_gif(self, path: Path) -> Path:
        """Write the animation as a looping GIF with the true frame durations."""
        images = [Image.fromarray(frame) for frame in self.frames()]
        palette = images[0].quantize(colors=128, method=Image.Quantize.MEDIANCUT)
        quantized = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
        path.parent.mkdir(parents=True, exist_ok=True)
        quantized[0].save(
            path,
            save_all=True,
            append_images=quantized[1:],
            loop=0,
            duration=self.durations_ms,
            disposal=1,
            optimize=False,
        )
        return path

    def save_mp4(self, path: Path) -> Path | None:
        """Write an H.264 MP4 at the frame rate of the schedule; ``None`` when ffmpeg is missing."""
        try:
            import imageio_ffmpeg
        except ImportError:
            return None
        frames = self.frames()
        height, width = frames[0].shape[:2]
        height, width = height - height % 2, width - width % 2  # yuv420p: even sizes only
        frames = [np.ascontiguousarray(frame[:height, :width]) for frame in frames]
        fps = self.speedup / (self.stride * self.dt)
        path.parent.mkdir(parents=True, exist_ok=True)
        writer = imageio_ffmpeg.write_frames(
            str(path),
            (width, height),
            fps=fps,
            codec="libx264",
            pix_fmt_out="yuv420p",
            macro_block_size=1,
            output_params=["-loglevel", "error"],
        )
        writer.send(None)
        for frame in frames + [frames[-1]] * max(0, math.ceil(self.hold * fps) - 1):
            writer.send(frame)
        writer.close()
        return path

    def close(self) -> None:
        """Release the figure's artists (the figure is not registered anywhere else) and the
        frames drawn."""
        self.fig.clear()
        self._frames = None


def run_is_pose(run: Run) -> bool:
    """True when the run tracks a pose (its error mixes metres and radians)."""
    return bool(run.e.shape[1] == 6)


def animate(
    runs: Sequence[Run],
    out_stem: Path,
    *,
    speedup: float = 1.0,
    max_fps: float = 20.0,
    mp4: bool = True,
) -> list[Path]:
    """Write ``<stem>.gif`` (and ``<stem>.mp4`` where ffmpeg is available) for ``runs``."""
    animator = Animator(runs, speedup=speedup, max_fps=max_fps)
    try:
        written = [animator.save_gif(out_stem.with_suffix(".gif"))]
        if mp4:
            video = animator.save_mp4(out_stem.with_suffix(".mp4"))
            if video is not None:
                written.append(video)
    finally:
        animator.close()
    return written


__all__ = ["Animator", "animate", "ellipse_points", "frame_schedule"]
