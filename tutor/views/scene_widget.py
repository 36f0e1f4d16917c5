"""The 3-D scene's output: its notebook widget, the page's messages and the static page.

:class:`SceneWidgetMixin` is the half of :class:`~tutor.views.scene3d.Scene3D` that shows
what the drawing half recorded: the ipywidget (the caption with the legend, Replay and
the viewer in its frame, :func:`~tutor.views.scene_page.viewer_widget_class`), the
changes it sends to the notebook viewer at :meth:`~SceneWidgetMixin.refresh`, the
messages the page sends back (a browser opened the view; guiding,
:mod:`tutor.views.scene_guide`), the "working" line over the view, the stamp the live
viewer records after each update, and the scene as one self-contained page
(:meth:`~SceneWidgetMixin.static_html`, :meth:`~SceneWidgetMixin.save_html`). It draws
nothing itself: :mod:`tutor.views.scene3d` draws.
"""

from __future__ import annotations

import contextlib
import html
from pathlib import Path

from ..errors import InvalidParameterError, InvalidPayloadError
from ..fileio import atomic_write_text
from ..payloads import check_view_message, safely
from .meshcat_recorder import frame_commands
from .scene_guide import GUIDE_MESSAGES
from .scene_meshes import HAND_CLOSED, HAND_OPEN
from .scene_page import live_page_url, page, scene_data, viewer_widget_class
from .style import DEMO, FAIL, PASS, UNKNOWN

__all__ = ["SceneWidgetMixin", "STAMP", "WORKING"]

#: The path of the live viewer's "update applied" stamp (its page handles it; not drawn).
STAMP = "/lfd-stamp"
#: What the view says while the kernel learns from a demonstration
#: (:meth:`SceneWidgetMixin.working`).
WORKING = "Working: the robot is learning from your demo..."


class SceneWidgetMixin:
    """The output of :class:`~tutor.views.scene3d.Scene3D` (see the module docstring).

    It uses what :class:`~tutor.views.scene3d.Scene3D` sets up: ``mode``, ``height``,
    ``message``, ``animation``, ``recorder``, ``scene_id``, ``replay_button``, the
    robot's meshes ``_robot``, ``_widget``, ``_view``, ``_pending``, ``_working``,
    ``_stamp`` and ``_guide``, and its :meth:`~tutor.views.scene3d.Scene3D.replay`;
    a guide message goes to ``_guide_message``
    (:class:`~tutor.views.scene_guide.GuidingMixin`).
    """

    def _check_live(self) -> None:
        if self.mode == "live" and self.recorder.live is None:
            self.mode = "static"
            self.message = (
                f"{self.recorder.live_error or 'no live viewer'}: showing the scene in the "
                "notebook instead."
            )

    def _stamp_live(self) -> None:
        """Tell the live viewer that an update is complete: its page (the tutor's, see
        :mod:`tutor.views.meshcat_server`) records the number and the time it applied
        it (``document.body.dataset.updates`` and ``.appliedAt``)."""
        if self.recorder.live is None:
            return
        import umsgpack

        self._stamp += 1
        command = {
            "type": "set_property",
            "path": STAMP,
            "property": "update",
            "value": self._stamp,
        }
        self.recorder.forward("set_property", STAMP, umsgpack.packb(command))

    def _scene_chunks(self) -> list[bytes]:
        """The whole scene as gzipped command frames: the robot's meshes (cached), the rest."""
        robot_ids = set()
        chunks = []
        if self._robot is not None:
            robot_ids = {id(c[2]) for c in self._robot.commands}
            chunks.append(self._robot.gz)
        rest = [c for c in self.recorder.commands() if id(c[2]) not in robot_ids]
        chunks.append(frame_commands(rest))
        return chunks

    def static_html(self, title: str = "lfd-tutor: pick and place in 3-D") -> str:
        """The scene as one self-contained HTML page (meshcat's viewer script inside)."""
        chunks = self._scene_chunks()
        if self._robot is not None:  # its base64 is cached too
            chunks[0] = self._robot.chunk
        caption = html.escape(self.animation.label if self.animation else "")
        return page(title, scene_data(chunks), self.legend_html(), caption)

    def save_html(self, path) -> Path:
        """Write :meth:`static_html` to ``path`` (atomically); returns the path.

        Raises
        ------
        SaveError
            In plain words: a name or path too long, no permission, a full disk
            (:func:`tutor.fileio.atomic_write_text`).
        """
        return atomic_write_text(path, self.static_html())

    @staticmethod
    def legend_html() -> str:
        dot = (
            "<span style='display:inline-block;width:11px;height:11px;border-radius:50%;"
            "background:{};margin:0 4px 0 10px;vertical-align:middle'></span>{}"
        )
        line = (
            "<span style='display:inline-block;width:16px;height:3px;background:{};"
            "margin:0 4px 0 10px;vertical-align:middle'></span>{}"
        )
        items = [
            dot.format(PASS, "succeeds"),
            dot.format(FAIL, "fails"),
            dot.format(DEMO, "demonstrated"),
            dot.format(UNKNOWN, "not seen yet"),
            line.format(DEMO, "your demos"),
            dot.format(HAND_OPEN, "hand open"),
            dot.format(HAND_CLOSED, "hand closed"),
        ]
        return "<span style='font-size:12px'>" + "".join(items) + "</span>"

    def _make_view(self):
        """The viewer widget: meshcat's page in a frame, from the live server (``src``) or
        fed over the widget's comm (``page``); both pass the guide's messages."""
        cls = viewer_widget_class()
        if self.mode == "live":
            url = live_page_url(self.recorder.web_url or "", self.scene_id)
            view = cls(height=self.height, src=url)
        else:
            view = cls(height=self.height, page=page("3-D view", "", "", ""))
            self.recorder.listeners.append(self._collect)
        view.on_msg(self._on_view_msg)
        return view

    def _collect(self, kind, path, packed) -> None:
        if self._pending is not None:  # a browser shows the view: keep what changes
            self._pending.append((kind, path, packed))

    def _on_view_msg(self, _widget, content, buffers) -> None:
        """A message from the page's view (:meth:`receive`). One the tutor does not
        understand is said in the caption and changes nothing (a refused guide message
        is answered, so that the page guides on); nothing raises out of here."""

        def act():
            try:
                self.receive(content, buffers)
            except InvalidPayloadError as exc:
                kind = content.get("type") if isinstance(content, dict) else None
                if self._guide is not None and kind in GUIDE_MESSAGES:
                    self._send_view(
                        {"type": "guide", "cmd": "refused", "what": kind, "words": str(exc)}
                    )
                raise

        def say(text: str) -> None:
            self.message = f"{text[:1].upper()}{text[1:]}" + ("" if text.endswith(".") else ".")
            self.refresh()

        safely(act, say)

    def receive(self, content, buffers=()) -> None:
        """Act on a message the page's view sent: a hello (a browser opened the view: the
        whole scene goes to it, then changes only) or the guide's move, end or cancel
        (:mod:`tutor.views.scene_guide`).

        Raises
        ------
        InvalidPayloadError
            A message the tutor does not know, or a guide message that is not one
            (:mod:`tutor.payloads`); nothing changes and guiding goes on.
        """
        kind = content.get("type") if isinstance(content, dict) else None
        if kind in GUIDE_MESSAGES:
            self._guide_message(kind, content, list(buffers or []))
            return
        view = check_view_message(content)
        if view is None:
            return
        if self.mode == "static":
            # a browser (re)opened the view: send it the whole scene, then changes only
            self._pending = []
            self._send_view({"type": "full", "to": view}, self._scene_chunks())
        if self._guide is not None:  # a reloaded page is armed again
            self._send_view(self._guide.start_message())

    def _send_view(self, content: dict, buffers=None) -> None:
        if self._view is not None:
            self._view.send(content, buffers)

    def _flush(self) -> None:
        if self._pending:
            self._view.send({"type": "update"}, [frame_commands(self._pending)])
            self._pending = []

    def _caption_html(self) -> str:
        parts = [self.legend_html()]
        if self.animation is not None:
            parts.append(f"<div><b>Animated:</b> {html.escape(self.animation.label)}</div>")
        how = (
            "The attempt plays once by itself after each step; <b>Replay</b> plays it again. "
            "Drag to turn, right-drag to move; click the view, then scroll to zoom "
            "(Escape gives the wheel back to the page)."
        )
        if self.mode == "live" and self.recorder.web_url:
            url = html.escape(live_page_url(self.recorder.web_url, self.scene_id))
            how += f" <a href='{url}' target='_blank'>Open in its own tab</a>."
        parts.append(f"<div style='font-size:12px;color:#555'>{how}</div>")
        if self.message:
            parts.append(f"<div class='lfd-message'>{html.escape(self.message)}</div>")
        if self._working:
            parts.append(
                "<div class='lfd-working' role='status' style='font-weight:bold'>"
                f"&#8987; {html.escape(self._working)}</div>"
            )
        return "".join(parts)

    @property
    def widget(self):
        """The view as an ipywidget (caption, legend and the viewer)."""
        if self._widget is None:
            import ipywidgets as w

            self._caption = w.HTML()
            self.replay_button = w.Button(
                description="Replay",
                icon="play",
                tooltip="Play the robot's motion shown here again",
                layout=w.Layout(width="100px", flex="0 0 auto"),
            )
            self.replay_button.add_class("lfd-replay")
            self.replay_button.on_click(lambda _: self.replay())
            self._view = self._make_view()
            self._header = w.HBox([self.replay_button, self._caption])
            self._widget = w.VBox([self._header, self._view])
            self._widget.add_class("lfd-scene3d")
            self.refresh()
        return self._widget

    def refresh(self) -> None:
        """Update the widget: the caption (the :meth:`working` line goes), and the changes
        for the notebook viewer."""
        if self._widget is None:
            self._working = ""
            return
        was_working, self._working = self._working, ""
        self._caption.value = self._caption_html()
        if was_working and isinstance(self._view, viewer_widget_class()):
            self._view.send({"type": "working", "text": ""})
        self.replay_button.disabled = self.animation is None
        if self.mode == "static" and not self._view.src:
            self._flush()
        elif self.mode == "static":  # the live viewer died: switch to the notebook viewer
            self._view = self._make_view()
            self._widget.children = (self._header, self._view)

    def working(self, text: str = WORKING) -> None:
        """Say ``text`` over the view now (the caption's line and, in the notebook viewer,
        a line over the picture) until the next :meth:`refresh`.

        Call it before a slow step (a demonstration the robot learns from, a batch of
        tests): the line reaches the browser at once, while the step runs.

        Raises
        ------
        InvalidParameterError
            ``text`` is not a non-empty string of at most 200 characters.
        """
        if not (isinstance(text, str) and 0 < len(text.strip()) <= 200):
            raise InvalidParameterError(
                f"the working line must be a text of 1 to 200 characters, got {text!r}"
            )
        self._working = text.strip()
        self._show_working()

    @contextlib.contextmanager
    def busy(self, text: str = WORKING):
        """``with scene.busy(): ...``: :meth:`working` for the block; the line goes when
        the block ends, even if the block drew nothing (or raised)."""
        self.working(text)
        try:
            yield self
        finally:
            if self._working:
                self.refresh()

    def _show_working(self) -> None:
        if self._widget is None:
            return
        self._caption.value = self._caption_html()
        if isinstance(self._view, viewer_widget_class()):
            self._view.send({"type": "working", "text": self._working})

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
