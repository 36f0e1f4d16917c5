"""The responsive 3-D view (issue 20, part B), kernel side and page assembly.

- Both 3-D pages (the notebook viewer's and the live server's) carry scene3d_render.js,
  which builds the viewer (on-demand, capped drawing; tests/browser/test_render_browser.py
  checks what it does in chromium).
- :meth:`Scene3D.working` shows a line at once (the caption, and a message to the notebook
  viewer's page) that the next refresh clears; :meth:`Scene3D.busy` clears it after its
  block even when the block drew nothing or raised; bad text is a named error and changes
  nothing.
"""

from __future__ import annotations

import pytest

from tutor.errors import InvalidParameterError
from tutor.views.scene3d import Scene3D
from tutor.views.scene_widget import WORKING


def test_both_3d_pages_build_the_viewer_with_the_render_script():
    from tutor.views.scene_page import live_page, page, static_text

    render = static_text("scene3d_render.js")
    assert "window.lfdRender" in render and "lfdViewer" in render
    for text in (live_page(), page("t", "", "", "")):
        assert "{{" not in text
        assert render in text
        # the render script comes after meshcat's and before the page's own
        assert text.index("window.lfdViewer = ") < text.index("window.lfdViewer(document")
        assert "new MeshCat.Viewer(document" not in text  # meshcat's own loop is not started


def _scene(task):
    scene = Scene3D(task, mode="static", robot=False)
    view = scene.widget.children[1]
    sent = []
    view.send = lambda content, buffers=None: sent.append((content, buffers))
    scene._on_view_msg(view, {"type": "hello", "id": "v"}, [])
    sent.clear()
    return scene, sent


def test_working_line_shows_at_once_and_goes_at_the_next_refresh(pickplace_task):
    scene, sent = _scene(pickplace_task)
    scene.working()
    assert WORKING in scene._caption.value and "lfd-working" in scene._caption.value
    assert sent == [({"type": "working", "text": WORKING}, None)]
    sent.clear()
    scene.refresh()
    assert "lfd-working" not in scene._caption.value
    assert sent == [({"type": "working", "text": ""}, None)]
    sent.clear()
    scene.refresh()
    assert sent == []  # nothing to clear, nothing sent


def test_busy_clears_the_line_even_when_the_block_fails(pickplace_task):
    scene, sent = _scene(pickplace_task)
    with pytest.raises(RuntimeError), scene.busy("Working: testing 5 plants..."):
        assert "testing 5 plants" in scene._caption.value
        raise RuntimeError("the step failed")
    assert "lfd-working" not in scene._caption.value
    assert sent[-1] == ({"type": "working", "text": ""}, None)
    with scene.busy():
        scene.refresh()  # the block's own refresh cleared it: nothing more is sent
    assert sent[-1] == ({"type": "working", "text": ""}, None)


@pytest.mark.parametrize("text", ["", "   ", None, 3, "x" * 201])
def test_bad_working_text_is_a_named_error_and_changes_nothing(pickplace_task, text):
    scene, sent = _scene(pickplace_task)
    before = scene._caption.value
    with pytest.raises(InvalidParameterError, match="working line"):
        scene.working(text)
    assert scene._caption.value == before and sent == []


def test_working_before_the_widget_is_shown_is_harmless(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    scene.working()
    scene.refresh()
    assert "lfd-working" not in scene.widget.children[0].children[1].value
