"""The kernel's side of guiding the arm with one's own hand in the 3-D view.

The page (``tutor/views/static/guide.js``, in both 3-D pages) draws a handle at the
gripper and moves it with the mouse, the keys or a gamepad; it records
(t, x, y, z, g) every 25 ms from the first move to Enter and sends the recording once,
at the end, as the maze's sketchpad sends a stroke. Nothing it records waits for the
kernel. While the trainee guides, each move (at most one in flight) also comes here:
:class:`Guide` steps the task's own inverse kinematics
(:class:`tutor.robot.follow.HandFollower`) and answers with the links' placements, so
that the page draws the whole arm where the hand is, a link in collision in red and
the words saying what is wrong (out of reach, on the table).
:class:`GuidingMixin` gives :class:`~tutor.views.scene3d.Scene3D` its part: it arms a
:class:`Guide` (``start_guide``), stops it and hands it the page's messages.

Messages (widget custom messages; :mod:`tutor.views.scene_page`'s widget passes them
between the page in its frame and the kernel):

kernel -> page
    ``{"type": "guide", "cmd": "start", "start": [x, y, z], "grip", "limits":
    {"x": [lo, hi], "y": .., "z": ..}, "table", "words", "links": [node path, ...], "hand":
    path}``: arm the guide; ``{"type": "guide", "cmd": "arm", "seq", "position",
    "target", "grip", "reached", "collision", "clamped", "words", "red": [link index,
    ...]}`` with one buffer of the links' 4 x 4 placements (float32, column-major, as
    three.js reads them): the answer to move ``seq``; ``{"type": "guide", "cmd":
    "refused", "words"}``: the recording was refused, guide again;
    ``{"type": "guide", "cmd": "stop"}``: guiding is over.
page -> kernel
    ``{"type": "guide-move", "seq", "x", "y", "z", "g"}``
    (:func:`~tutor.payloads.check_guide_move`); ``{"type": "guide-end", "n",
    "setup"}`` with one buffer of n * 5 float64
    (:func:`~tutor.payloads.check_guide_end`); ``{"type": "guide-cancel"}``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..payloads import check_guide_end, check_guide_move

__all__ = ["GuideEnd", "Guide", "GuidingMixin", "GUIDE_MESSAGES"]

#: the message types the page sends while guiding
GUIDE_MESSAGES = ("guide-move", "guide-end", "guide-cancel")


@dataclass(frozen=True)
class GuideEnd:
    """A guided demonstration as the page recorded it.

    Attributes
    ----------
    raw : ndarray (T, 5)
        t (s from the first move), x, y, z (m, robot base frame), g (0 open .. 1 closed)
        per sample, as it arrived (only its form was checked:
        :func:`tutor.tasks.recording.check_recording` judges it).
    setup_seconds : float
        From arming the guide to the first move (s): it counts on the run's clock.
    """

    raw: np.ndarray
    setup_seconds: float


def _link_of(node: str) -> str:
    """The robot link a visual node draws ('robot/visuals/panda_link5_0' -> 'panda_link5')."""
    return re.sub(r"_\d+$", "", node.rsplit("/", 1)[-1])


class Guide:
    """One guiding in progress: the follower and what to call at the end.

    Parameters
    ----------
    follower : HandFollower
        Steps the arm to the handle (``reset()``, ``step(target, grip)``).
    on_end : callable(GuideEnd)
        Called once with the recording when the trainee presses Enter.
    on_cancel : callable() or None
        Called when the trainee presses Escape.
    links : sequence of str
        The Meshcat paths of the robot's visual links, in the order of the follower's
        placements (what the page moves).
    hand : str
        The Meshcat path of the hand marker.
    limits : dict
        The handle's box, ``{"x": [lo, hi], "y": .., "z": ..}`` (m).
    table : float
        The table top's height (m): the handle's shadow is drawn there.
    """

    def __init__(
        self,
        follower,
        on_end: Callable[[GuideEnd], object],
        on_cancel: Callable[[], object] | None,
        links: Sequence[str],
        hand: str,
        limits: dict,
        table: float = 0.0,
    ):
        for name in ("reset", "step"):
            if not callable(getattr(follower, name, None)):
                raise InvalidParameterError(
                    f"follower must be a HandFollower (with reset and step), got {follower!r}"
                )
        if not callable(on_end) or not (on_cancel is None or callable(on_cancel)):
            raise InvalidParameterError("on_end (and on_cancel, if given) must be callables")
        self.follower = follower
        self.on_end = on_end
        self.on_cancel = on_cancel
        self.links = [str(p) for p in links]
        self._link_names = [_link_of(p) for p in self.links]
        self.hand = str(hand)
        self.limits = {k: [float(v) for v in limits[k]] for k in "xyz"}
        self.table = float(table)
        self.state = follower.reset()
        self.moves = 0  # moves answered

    def start_message(self) -> dict:
        """What arms the page: where the handle starts, its box, the links to move."""
        s = self.state
        return {
            "type": "guide",
            "cmd": "start",
            "start": [float(v) for v in s.position],
            "grip": float(s.grip),
            "limits": self.limits,
            "table": self.table,
            "words": s.words,
            "links": self.links,
            "hand": self.hand,
        }

    def move(self, content) -> tuple[dict, list[bytes]]:
        """Step the follower to a ``guide-move`` and return the answer (message, buffers).

        Raises
        ------
        InvalidPayloadError
            A move that is not one (:func:`~tutor.payloads.check_guide_move`); the
            arm stays where it was.
        """
        seq, target, grip = check_guide_move(content)
        state = self.follower.step(target, grip)
        self.state = state
        self.moves += 1
        message = {"type": "guide", "cmd": "arm", "seq": seq, **state.to_message()}
        message["red"] = [i for i, n in enumerate(self._link_names) if n == state.collision]
        P = np.asarray(state.placements, dtype=np.float32)
        if P.shape != (len(self.links), 4, 4):
            raise InvalidParameterError(
                f"the follower gave {P.shape[0] if P.ndim == 3 else P.shape} placements for "
                f"{len(self.links)} links: is it the scene's own arm?"
            )
        return message, [np.ascontiguousarray(P.transpose(0, 2, 1)).tobytes()]

    @staticmethod
    def end(content, buffers) -> GuideEnd:
        """The :class:`GuideEnd` of a ``guide-end`` message (checked, not yet judged).

        Raises
        ------
        InvalidPayloadError
            See :func:`~tutor.payloads.check_guide_end`.
        """
        raw, setup = check_guide_end(content, buffers)
        return GuideEnd(raw, setup)


class GuidingMixin:
    """Guiding the arm in :class:`~tutor.views.scene3d.Scene3D`: start, stop, the page's moves.

    It uses what :class:`~tutor.views.scene3d.Scene3D` sets up: ``scene``, the robot's
    meshes ``_robot``, ``_guide``, ``message``, and its drawing
    (``_node_path``, ``clear_animation``, ``show_configuration``) and output
    (``refresh``, ``_stamp_live``, ``_send_view``:
    :class:`~tutor.views.scene_widget.SceneWidgetMixin`).
    """

    @property
    def guiding(self) -> bool:
        """Whether the trainee is guiding the arm in this view now."""
        return self._guide is not None

    def start_guide(self, follower, on_end, on_cancel=None) -> None:
        """Let the trainee guide the arm with the handle in the view (keys, mouse, gamepad).

        The animation stops and the robot goes to the follower's start; the page arms its
        guide. When the trainee presses Enter, ``on_end`` gets the recording
        (:class:`~tutor.views.scene_guide.GuideEnd`); Escape calls ``on_cancel``. After
        either, the view shows the arm at its start again.

        Parameters
        ----------
        follower : HandFollower
            :class:`tutor.robot.follow.HandFollower` of this scene.
        on_end : callable(GuideEnd)
        on_cancel : callable(), optional
        """
        from ..robot.follow import guide_limits

        sc = self.scene
        links = [self._node_path(n) for n in self._robot.node_names] if self._robot else []
        top = float(sc.table_center[2] + sc.table_size[2] / 2)
        guide = Guide(
            follower,
            on_end,
            on_cancel,
            links,
            self._node_path("lfd/hand"),
            guide_limits(sc),
            table=top,
        )
        self.clear_animation()
        self.show_configuration(guide.state.q)
        self._guide = guide
        self.refresh()
        self._stamp_live()
        self._send_view(guide.start_message())

    def stop_guide(self) -> None:
        """Stop guiding (no callback is called); the view shows the arm at its start."""
        if self._guide is None:
            return
        self._guide = None
        self._send_view({"type": "guide", "cmd": "stop"})
        self.show_configuration(self.scene.start_configuration)
        self.refresh()
        self._stamp_live()

    def _guide_message(self, kind: str, content: dict, buffers: list) -> None:
        guide = self._guide
        if guide is None:
            return  # a move still on its way when guiding stopped
        if kind == "guide-move":
            self._send_view(*guide.move(content))
        elif kind == "guide-end":
            end = guide.end(content, buffers)
            self.stop_guide()
            self.message = ""
            guide.on_end(end)
        else:
            self.stop_guide()
            if guide.on_cancel is not None:
                guide.on_cancel()
