"""The page itself: the HTML template with its CSS, JavaScript and data inlined.

Browsers refuse ``fetch()`` of files next to a page opened from ``file://``, so the page carries its
data in a ``<script type="application/json">`` element; the per-lens maps (sharpest slice, distance,
confidence) travel as base64 of their little-endian bytes, decoded into typed arrays by the script.
No file is loaded from the network: the template references only the page's own images.
"""

from __future__ import annotations

import base64
import html
import json
from importlib import resources

import numpy as np

from ..atomic import json_safe


def _asset(name: str) -> str:
    return resources.files(__package__).joinpath("assets", name).read_text(encoding="utf-8")


def encode_array(array: np.ndarray) -> dict:
    """``{"dtype", "shape", "base64"}`` of a uint8 or float32 array (little-endian, row-major);
    non-finite floats are kept (infinity = beyond every slice, NaN = unknown)."""
    array = np.ascontiguousarray(array)
    dtype = {np.dtype(np.uint8): "uint8", np.dtype(np.float32): "float32"}[array.dtype]
    raw = array.astype(array.dtype.newbyteorder("<"), copy=False).tobytes()
    return {"dtype": dtype, "shape": list(array.shape), "base64": base64.b64encode(raw).decode("ascii")}


def script_json(obj) -> str:
    """Strict JSON safe inside a ``<script>`` element (no ``</script>`` or ``<!--`` can end it early)."""
    text = json.dumps(json_safe(obj), allow_nan=False, separators=(",", ":"))
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def render_page(data: dict, maps: dict) -> str:
    """The viewer page for one capture (``data`` as in geometry.json, ``maps`` from :func:`encode_array`)."""
    return (_asset("page.html")
            .replace("{{TITLE}}", html.escape(f"lfproc viewer: {data['stem']}"))
            .replace("{{CSS}}", _asset("viewer.css"))
            .replace("{{DATA}}", script_json(data))
            .replace("{{MAPS}}", script_json(maps))
            .replace("{{JS}}", _asset("viewer.js")))


def render_index(entries: list[dict]) -> str:
    """The index of several captures: ``entries`` of ``{"stem", "href", "thumbnail", "source", "slices"}``."""
    cards = []
    for entry in entries:
        cards.append(
            f'<a class="card" href="{html.escape(entry["href"])}">'
            f'<img src="{html.escape(entry["thumbnail"])}" alt="{html.escape(entry["stem"])}">'
            f'<span class="name">{html.escape(entry["stem"])}</span>'
            f'<span class="meta">{entry["slices"]} slices, {html.escape(entry["range"])}</span>'
            f'<span class="meta">{html.escape(entry["source"])}</span></a>')
    return (_asset("index.html")
            .replace("{{CSS}}", _asset("viewer.css"))
            .replace("{{COUNT}}", str(len(entries)))
            .replace("{{CARDS}}", "\n".join(cards)))
