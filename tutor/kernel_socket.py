"""The kernel's websocket without Nagle's delay: the 3-D view's answers arrive at once.

Jupyter Server (and Voila, which uses its handlers) never calls tornado's
``WebSocketHandler.set_nodelay``, so the server's small writes to the browser wait for the
browser's ACK of the one before (Nagle's algorithm), and the browser delays its ACKs by up
to 40 ms (Linux's delayed ACK). A widget's message from the kernel that follows another
one (the kernel's "busy" status, say) then reaches the page about 43 ms late: measured
here, a comm message's round trip through the server's websocket took a median 45.8 ms,
of which 2 ms to the kernel and back; with this connection class it takes about 3 ms.
That delay was most of the time from the trainee moving the handle to the arm drawn at
its new pose (``tutor.views.scene_guide``).

:class:`NoDelayKernelConnection` is Jupyter Server's own kernel connection with
``TCP_NODELAY`` set once the websocket is open. This module is also a Jupyter Server
extension that makes it the server's kernel connection (JupyterLab, the hub's single-user
servers): ``etc/jupyter/jupyter_server_config.d/lfd-tutor.json`` enables it. Voila, which
loads no server extensions, takes it from ``etc/jupyter/voila.json``
(``Voila.kernel_websocket_connection_class``). ``scripts/env.sh`` copies both into the
environment's ``etc/jupyter``, and the wheel installs them. It imports nothing of the
tutor (the server stays light).

It also lets the server's subscription to a kernel's output (IOPub) queue without bound.
ZeroMQ's default high-water mark is 1000 messages a socket: when the server's event loop
is busy (a loaded machine, a room on one hub) while the kernel sends a burst, the
subscription fills and the kernel's publisher then *drops* messages silently. Building a
pick-and-place run sends about 1400 widget messages in a fraction of a second; one lost
message (the stage's children, a status "idle") left a run's tutor missing from the page
for good (seen in CI under load, three times). With no high-water mark on the
subscribing side, ZeroMQ's I/O thread, which runs without the server's event loop or
Python's lock, keeps draining the kernel's messages into the server's memory until the
loop reads them; the server holds them for the browser in any case.
"""

from __future__ import annotations

import zmq
from jupyter_server.services.kernels.connection.channels import (
    ZMQChannelsWebsocketConnection,
)


class NoDelayKernelConnection(ZMQChannelsWebsocketConnection):
    """Jupyter Server's kernel websocket connection, with Nagle's algorithm off.

    Examples
    --------
    In ``jupyter_server_config.json``::

        {"ServerApp": {"kernel_websocket_connection_class":
            "tutor.kernel_socket.NoDelayKernelConnection"}}
    """

    def connect(self):
        """Connect as Jupyter Server does, after turning Nagle's algorithm off."""
        handler = self.websocket_handler
        if handler is not None and handler.ws_connection is not None:
            handler.set_nodelay(True)
        return super().connect()

    def create_stream(self):
        """The kernel's channels as Jupyter Server opens them, never dropping output."""
        unbounded_queues(self.kernel_manager.context)
        return super().create_stream()


def unbounded_queues(context: zmq.Context) -> None:
    """Let the sockets ``context`` opens from now on queue received messages without
    bound (no receive high-water mark), so that a kernel's burst is never dropped."""
    context.setsockopt(zmq.RCVHWM, 0)


def _jupyter_server_extension_points() -> list[dict]:
    """Jupyter Server's entry point: this module is the extension."""
    return [{"module": "tutor.kernel_socket"}]


def _load_jupyter_server_extension(serverapp) -> None:
    """Make :class:`NoDelayKernelConnection` the server's kernel websocket connection
    (the handlers read it from the web app's settings at each connection)."""
    settings = serverapp.web_app.settings
    current = settings.get("kernel_websocket_connection_class")
    if current in (None, ZMQChannelsWebsocketConnection) and not _configured(serverapp):
        settings["kernel_websocket_connection_class"] = NoDelayKernelConnection
        serverapp.log.info("lfd-tutor: kernel websockets without Nagle's delay")
    else:  # a gateway's, or one the user configured: theirs stands
        serverapp.log.info(f"lfd-tutor: kernel websockets left as {current.__name__}")


def _configured(serverapp) -> bool:
    """Whether the user set ``ServerApp.kernel_websocket_connection_class`` themself."""
    return "kernel_websocket_connection_class" in serverapp.config.get("ServerApp", {})
