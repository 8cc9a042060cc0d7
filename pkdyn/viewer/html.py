"""The static HTML page of a meshcat scene: viewer JavaScript inlined, commands replayed in order.

meshcat's own ``static_html`` needs its ZMQ server and replays the commands through ``fetch`` of
``data:`` URLs, whose promises may resolve in any order (an animation can then bind to objects not
created yet). This page decodes the commands synchronously, in order, and loads nothing from the
network or the disk: it opens from a file, an e-mail attachment or a web server alike.
"""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from functools import cache
from pathlib import Path

import meshcat

__all__ = ["static_html", "viewer_javascript"]


@cache
def viewer_javascript() -> str:
    """The bundled meshcat viewer (three.js and the MeshCat API), as shipped with the package."""
    path = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    text = path.read_text(encoding="utf-8")
    if "</script" in text:  # would end the inline <script> early
        text = text.replace("</script", "<\\/script")
    return text


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{viewer}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
(function () {{
  var commands = [
{commands}
  ];
  for (var i = 0; i < commands.length; i++) {{
    var raw = atob(commands[i]);
    var bytes = new Uint8Array(raw.length);
    for (var k = 0; k < raw.length; k++) {{ bytes[k] = raw.charCodeAt(k); }}
    viewer.handle_command_bytearray(bytes);
  }}
  document.body.setAttribute("data-pkdyn-commands", String(commands.length));
}})();
</script>
</body>
</html>
"""


def static_html(commands: Sequence[bytes], title: str = "pkdyn viewer") -> str:
    """A self-contained HTML page that replays msgpack-encoded meshcat commands.

    Args:
        commands: meshcat commands (msgpack bytes, as sent to the server), replayed in order.
        title: Page title.

    Returns:
        The HTML document (viewer JavaScript included, about 0.9 MB plus the scene).

    """
    from pkdyn.exceptions import InvalidInputError

    if not isinstance(title, str):
        raise InvalidInputError("title", f"expected a string, got {title!r:.40}")
    if isinstance(commands, str | bytes | dict) or not all(
        isinstance(c, bytes) for c in (commands if hasattr(commands, "__iter__") else [None])
    ):
        raise InvalidInputError("commands", "expected a sequence of bytes (meshcat commands)")
    lines = ",\n".join(f'    "{base64.b64encode(c).decode("ascii")}"' for c in commands)
    return _PAGE.format(title=html.escape(title), viewer=viewer_javascript(), commands=lines)
