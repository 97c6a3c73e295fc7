"""The scene's record of meshcat commands and its export as one self-contained HTML page.

A :class:`CommandLog` stands in for meshcat's window: it keeps every command of a scene (the
last one per node and kind, in order) and forwards them to a live meshcat server only once
one is asked for (:meth:`CommandLog.live`), so that writing a page starts no server.

:func:`static_html` writes the page the way meshcat's own export does (the viewer's script
and the commands as base64 msgpack blobs), with two differences: the commands are replayed
in their order, synchronously, and every mesh file is embedded once however many robots
use it (a ``swarm_ik_shared`` command carries the meshes; the others refer to them by key).
"""

from __future__ import annotations

import argparse
import base64
import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from swarm_ik._validate import check_output_path
from swarm_ik.errors import InvalidArgumentError

SHARED_PREFIX = "swarm_ik-shared:"
"""Prefix of a mesh reference in an exported command (followed by the mesh's key)."""
SHARED_COMMAND = "swarm_ik_shared"
"""Type of the exported command carrying the shared meshes (``data``: key -> mesh)."""


class _Lowered:
    """A lowered meshcat command (a dict) in the shape ``ViewerWindow.send`` takes."""

    def __init__(self, data: dict[str, Any]) -> None:
        self.data = data

    def lower(self) -> dict[str, Any]:
        return self.data


def _key(data: dict[str, Any]) -> tuple[str, ...]:
    kind, path = str(data["type"]), str(data.get("path", ""))
    if kind == "set_property":
        return (kind, path, str(data.get("property", "")))
    if kind == "set_animation":
        return (kind,)
    return (kind, path)


class CommandLog:
    """The commands of one scene; a meshcat "window" (``meshcat.Visualizer(window=log)``).

    Attributes:
        commands: The scene's commands (lowered dicts), in the order they were last set.
    """

    def __init__(self) -> None:
        self._log: dict[tuple[str, ...], dict[str, Any]] = {}
        self._live: Any = None

    @property
    def commands(self) -> list[dict[str, Any]]:
        return list(self._log.values())

    def send(self, command: Any) -> None:
        """Record a meshcat command (anything with ``lower()``); forward it when live."""
        data = command.lower()
        if data["type"] == "delete":
            path = str(data["path"])
            for key in [k for k in self._log if len(k) > 1 and _under(k[1], path)]:
                del self._log[key]
        else:
            key = _key(data)
            self._log.pop(key, None)
            self._log[key] = data
        if self._live is not None:
            self._live.send(command)

    @property
    def is_live(self) -> bool:
        return self._live is not None

    def live(self) -> Any:
        """The live meshcat window: started on first use (a local server on the loopback
        interface) and sent the whole scene so far."""
        if self._live is None:
            import contextlib
            import io

            from meshcat.visualizer import ViewerWindow

            with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
                window = ViewerWindow(zmq_url=None, start_server=True, server_args=[])
            for data in self._log.values():
                window.send(_Lowered(data))
            self._live = window
        return self._live

    @property
    def web_url(self) -> str:
        """URL of the live viewer (starts it)."""
        return str(self.live().web_url)

    def close(self) -> None:
        """Stop the live server, if one was started."""
        window, self._live = self._live, None
        if window is None:
            return
        sock = getattr(window, "zmq_socket", None)
        if sock is not None and not sock.closed:
            sock.close(linger=0)
        proc = getattr(window, "server_proc", None)
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
        for pipe in (getattr(proc, "stdout", None), getattr(proc, "stderr", None)):
            if pipe is not None and not pipe.closed:
                pipe.close()


def _under(path: str, root: str) -> bool:
    return path == root or path.startswith(root.rstrip("/") + "/")


# ------------------------------------------------------------------------ shared meshes
def _digest(value: Any) -> str:
    import umsgpack

    raw = umsgpack.packb(value)
    return hashlib.sha1(raw, usedforsecurity=False).hexdigest()[:16]


def share_meshes(commands: list[dict[str, Any]]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Take the mesh files out of ``set_object`` commands, each distinct one kept once.

    Args:
        commands: Lowered meshcat commands (not modified).

    Returns:
        ``(store, commands)``: key -> mesh data (file text, bytes or texture data URI), and
        copies of the commands whose mesh data is replaced by ``SHARED_PREFIX + key``.
    """
    store: dict[str, Any] = {}

    def ref(value: Any) -> Any:
        if value is None or (isinstance(value, str) and len(value) < 256):  # short: inline
            return value
        key = _digest(value)
        store.setdefault(key, value)
        return SHARED_PREFIX + key

    out = []
    for cmd in commands:
        obj = cmd.get("object") if cmd.get("type") == "set_object" else None
        if not isinstance(obj, dict):
            out.append(cmd)
            continue
        obj = dict(obj)
        geometries = []
        for g in obj.get("geometries", []):
            if isinstance(g, dict) and str(g.get("type", "")).startswith("_meshfile"):
                g = {**g, "data": ref(g.get("data"))}
            geometries.append(g)
        if "geometries" in obj:
            obj["geometries"] = geometries
        inner = obj.get("object")
        if isinstance(inner, dict) and str(inner.get("type", "")).startswith("_meshfile"):
            inner = {**inner, "data": ref(inner.get("data"))}
            if isinstance(inner.get("resources"), dict):
                inner["resources"] = {k: ref(v) for k, v in inner["resources"].items()}
            obj["object"] = inner
        out.append({**cmd, "object": obj})
    return store, out


_UNSHARE_JS = (
    """
var swarmIkShared = {};
var swarmIkHandle = viewer.handle_command.bind(viewer);
function swarmIkUnshare(x) {
  return (typeof x === "string" && x.startsWith("@PREFIX@"))
    ? swarmIkShared[x.slice(@N@)] : x;
}
viewer.handle_command = function (cmd) {
  if (cmd.type === "@COMMAND@") { Object.assign(swarmIkShared, cmd.data); return; }
  if (cmd.type === "set_object" && cmd.object) {
    (cmd.object.geometries || []).forEach(function (g) { g.data = swarmIkUnshare(g.data); });
    var o = cmd.object.object;
    if (o) {
      o.data = swarmIkUnshare(o.data);
      if (o.resources) {
        for (var k in o.resources) { o.resources[k] = swarmIkUnshare(o.resources[k]); }
      }
    }
  }
  swarmIkHandle(cmd);
};
function swarmIkLoad(uri) {
  var s = atob(uri.slice(uri.indexOf(",") + 1));
  var b = new Uint8Array(s.length);
  for (var i = 0; i < s.length; i++) { b[i] = s.charCodeAt(i); }
  viewer.handle_command_bytearray(b);
}
""".replace("@N@", str(len(SHARED_PREFIX)))
    .replace("@PREFIX@", SHARED_PREFIX)
    .replace("@COMMAND@", SHARED_COMMAND)
)


def static_html(commands: list[dict[str, Any]], title: str = "swarm_ik") -> str:
    """One self-contained HTML page replaying ``commands`` in meshcat's viewer (no server).

    Args:
        commands: Lowered meshcat commands, in order.
        title: The page's title.

    Returns:
        The page's text.
    """
    import html as html_lib

    import meshcat
    import umsgpack

    store, cmds = share_meshes(commands)
    if store:
        cmds = [{"type": SHARED_COMMAND, "path": "", "data": store}, *cmds]
    lines = []
    for cmd in cmds:
        blob = base64.b64encode(umsgpack.packb(cmd)).decode("ascii")
        lines.append(f'swarmIkLoad("data:application/octet-binary;base64,{blob}");')
    js = (Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js").read_text()
    return (
        "<!DOCTYPE html>\n<html>\n<head><meta charset=utf-8><title>"
        + html_lib.escape(title)
        + "</title>\n<style>body {margin: 0;} #meshcat-pane {width: 100vw; height: 100vh; "
        'overflow: hidden;}</style></head>\n<body>\n<div id="meshcat-pane"></div>\n'
        "<script>" + js + "</script>\n<script>\n"
        'var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));\n'
        + _UNSHARE_JS
        + "\n".join(lines)
        + "\n</script>\n</body>\n</html>\n"
    )


def output_file(*suffixes: str) -> Callable[[str], Path]:
    """An ``argparse`` type for an output file of a script (the examples' ``--html FILE``,
    ``--out FILE``): the path checked by :func:`check_output_path` when the arguments are
    parsed, so that a missing folder or a wrong suffix is one line and exit 2 before any work,
    not a traceback after it.

    Args:
        *suffixes: Valid suffixes (lower case, with the dot).
    """

    def parse(text: str) -> Path:
        try:
            return check_output_path(text, "the file", tuple(suffixes))
        except InvalidArgumentError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse
