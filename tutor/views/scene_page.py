"""How the recorded 3-D scene reaches a browser: live or static, a page, a widget.

``choose_mode`` picks a live Meshcat viewer (the kernel's loopback server) or the
static one (no server: the scene travels as recorded commands). For the static one,
:func:`page` builds meshcat's viewer page around gzipped command frames, and
:func:`viewer_widget_class` gives the anywidget that shows that page in an iframe
and feeds it the scene over the widget's comm.

The HTML, the page's script and the widget's script are static files in
``tutor/views/static/`` (``scene3d_page.html``, ``scene3d_page.js``,
``scene3d_view.js``; ``scene3d_live.html`` for the live server's page, and in both
pages ``scene3d_wheel.js``, the wheel scrolls the page until the view is clicked,
``scene3d_render.js``, the view draws on demand at a capped, adaptive frame rate and
pauses off screen, and ``guide.js``, guiding the arm with one's own hand), read with
:mod:`importlib.resources`. meshcat's own viewer script comes from the installed
meshcat package (it works offline).
"""

from __future__ import annotations

import base64
import html
import os
import re
from functools import lru_cache
from importlib.resources import files
from pathlib import Path
from urllib.parse import urlparse

from ..errors import InvalidParameterError
from ..runtime import headless

__all__ = [
    "LIVE_PAGE",
    "LIVE_SOCKET",
    "SCENE_ID",
    "choose_mode",
    "live_page",
    "live_page_url",
    "page",
    "scene_data",
    "static_text",
    "viewer_widget_class",
]

#: Where the tutor's Meshcat server serves the viewer page of each scene,
#: ``/lfd/<scene id>/`` (``scene3d_live.html``: meshcat's viewer, plus the "update
#: applied" stamp), next to meshcat's ``/static/``.
LIVE_PAGE = "/lfd/"
#: The websocket of each scene on that server, ``/lfd-ws/<scene id>``.
LIVE_SOCKET = "/lfd-ws/"
#: What a scene id may be (the tutor's are 32 hex digits): it is part of the page's address.
SCENE_ID = re.compile(r"[0-9a-z]{1,64}")

_SLOT = re.compile(r"\{\{(\w+)\}\}")


def choose_mode(mode: str = "auto") -> str:
    """``"live"`` or ``"static"`` for ``mode`` in {"auto", "live", "static"}.

    Auto is static when headless (``TUTOR_HEADLESS=1``), behind JupyterHub or on
    Binder, or in Voila opened from another machine (the live viewer is on the
    kernel's loopback, out of reach of a browser elsewhere), and live otherwise.
    """
    if mode not in ("auto", "live", "static"):
        raise InvalidParameterError(f"mode must be 'auto', 'live' or 'static', got {mode!r}")
    if mode != "auto":
        return mode
    remote = any(k in os.environ for k in ("JUPYTERHUB_SERVICE_PREFIX", "BINDER_SERVICE_HOST"))
    voila = os.environ.get("VOILA_REQUEST_URL")  # the address the browser asked Voila for
    if voila and urlparse(voila).hostname not in ("127.0.0.1", "localhost", "::1"):
        remote = True
    return "static" if headless() or remote else "live"


def live_page_url(web_url: str, scene_id: str) -> str:
    """The live viewer page of scene ``scene_id`` on the server whose meshcat page is
    ``web_url`` ("http://127.0.0.1:7000/static/", "ab12" ->
    "http://127.0.0.1:7000/lfd/ab12/"); "" stays ""."""
    if not web_url:
        return ""
    parsed = urlparse(web_url)
    return parsed._replace(path=f"{LIVE_PAGE}{scene_id}/", query="", fragment="").geturl()


def live_page() -> str:
    """The live viewer page (``scene3d_live.html`` with the wheel's, the renderer's and
    the guide's scripts in it); the page reads its scene id from its own address."""
    slots = {
        "wheel": static_text("scene3d_wheel.js"),
        "render": static_text("scene3d_render.js"),
        "guide": static_text("guide.js"),
    }
    return _SLOT.sub(lambda m: slots[m[1]], static_text("scene3d_live.html"))


@lru_cache(maxsize=8)
def static_text(name: str) -> str:
    """The text of ``tutor/views/static/<name>`` (read once per process)."""
    return (files("tutor.views") / "static" / name).read_text(encoding="utf-8")


@lru_cache(maxsize=1)
def _viewer_js() -> str:
    import meshcat

    path = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    return path.read_text(encoding="utf-8").replace("</script", "<\\/script")


def scene_data(chunks) -> str:
    """Gzipped command frames (bytes, or their base64 text) as the page's data scripts."""
    return "".join(
        '<script type="application/octet-stream" class="scene-data">'
        + (c if isinstance(c, str) else base64.b64encode(c).decode("ascii"))
        + "</script>"
        for c in chunks
    )


def page(title: str, data: str, legend: str, caption: str) -> str:
    """meshcat's viewer as one self-contained HTML page.

    Parameters
    ----------
    title : str
        The page title (escaped here).
    data : str
        The scene, from :func:`scene_data` ("" for a page fed later, the widget's).
    legend, caption : str
        HTML shown over the view, top left (none when both are empty).
    """
    overlay = (
        f'<div id="lfd-legend">{legend}<div id="lfd-caption">{caption}</div></div>'
        if legend or caption
        else ""
    )
    slots = {
        "title": html.escape(title),
        "overlay": overlay,
        "data": data,
        "viewer": _viewer_js(),
        "render": static_text("scene3d_render.js"),
        "script": static_text("scene3d_wheel.js")
        + static_text("scene3d_page.js")
        + static_text("guide.js"),
    }
    # one pass over the template: the data inserted is never searched for slots
    return _SLOT.sub(lambda m: slots[m[1]], static_text("scene3d_page.html"))


@lru_cache(maxsize=1)
def viewer_widget_class():
    """The anywidget class of the in-notebook viewer (built on first use)."""
    import anywidget
    import traitlets

    class SceneView(anywidget.AnyWidget):
        """meshcat's viewer in an iframe: the live server's page at ``src``, or ``page``
        fed over the widget's comm (the whole scene when a browser opens it, then only
        the changes: the camera stays put). Either way the widget passes the guide's
        messages between the page and the kernel (:mod:`tutor.views.scene_guide`)."""

        _esm = static_text("scene3d_view.js")
        height = traitlets.Int(480).tag(sync=True)
        page = traitlets.Unicode("").tag(sync=True)
        src = traitlets.Unicode("").tag(sync=True)

    return SceneView
