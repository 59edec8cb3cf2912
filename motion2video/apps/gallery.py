"""``index.html`` for a batch's output folder: every output video with its input, status and error.

One self-contained HTML file (no server, no network): the rows are embedded as JSON and a few lines of
JavaScript show them :data:`PAGE_SIZE` per page (``#page=N`` in the address keeps the page). Videos are
``<video>`` tags (GIFs ``<img>``) with ``src`` relative to the folder, so the folder can be moved or copied
whole. Only the visible page's videos are in the document, so a 10,000-job batch opens as fast as a small
one. Failed jobs show their one-line error in place of a video. Measured: Debian's chromium plays the
H.264 mp4s (``readyState`` 4), so no second encoding is written.
"""

from __future__ import annotations

import html
import json
import os
from pathlib import Path
from typing import Iterable

from motion2video.core.atomic import write_text

PAGE_SIZE = 50
INDEX_NAME = "index.html"

_TEMPLATE = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>__TITLE__</title>
<style>
body { font-family: sans-serif; margin: 1em; background: #fafafa; }
#summary { margin-bottom: .5em; }
#cells { display: grid; grid-template-columns: repeat(auto-fill, minmax(260px, 1fr)); gap: 12px; }
.cell { background: white; border: 1px solid #ccc; padding: 6px; font-size: 13px; overflow-wrap: anywhere; }
.cell video, .cell img { width: 100%; height: auto; background: black; display: block; }
.status-ok, .status-skipped { color: #176b1e; }
.status-failed { color: #b00020; font-weight: bold; }
.error { color: #b00020; font-family: monospace; white-space: pre-wrap; }
nav { margin: .8em 0; }
nav button { margin-right: .3em; }
</style>
</head>
<body>
<h1>__TITLE__</h1>
<div id="summary"></div>
<nav id="pager-top"></nav>
<div id="cells"></div>
<nav id="pager-bottom"></nav>
<script id="rows" type="application/json">__ROWS__</script>
<script>
const rows = JSON.parse(document.getElementById("rows").textContent);
const pageSize = __PAGE_SIZE__;
const pages = Math.max(1, Math.ceil(rows.length / pageSize));
const count = s => rows.filter(r => r.status === s).length;
document.getElementById("summary").textContent =
  `${rows.length} jobs: ${count("ok")} done, ${count("skipped")} skipped, ${count("failed")} failed`;

function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

function cell(r) {
  const c = el("div", {class: "cell", "data-status": r.status, "data-name": r.name});
  if (r.status === "failed") {
    c.appendChild(el("div", {class: "error"}, r.error || "failed"));
  } else if (/\\.gif$/i.test(r.src)) {
    c.appendChild(el("img", {src: r.src, alt: r.name}));
  } else {
    c.appendChild(el("video", {src: r.src, controls: "", muted: "", loop: "", preload: "auto",
                               playsinline: ""}));
  }
  c.appendChild(el("div", {class: "name"}, r.input || r.name));
  const meta = [r.status, r.frames !== null && r.frames !== undefined ? `${r.frames} frames` : null,
                r.seconds ? `${r.seconds.toFixed(1)} s` : null].filter(Boolean).join(" · ");
  c.appendChild(el("div", {class: "status-" + r.status}, meta));
  c.appendChild(el("div", {class: "output"}, r.name));
  return c;
}

function pager(page) {
  const nav = document.createElement("span");
  const add = (label, p) => {
    const b = el("button", {"data-page": p}, label);
    b.disabled = p === page || p < 1 || p > pages;
    b.onclick = () => show(p);
    nav.appendChild(b);
  };
  add("prev", page - 1);
  for (let p = 1; p <= pages; p++) add(String(p), p);
  add("next", page + 1);
  nav.appendChild(el("span", {class: "where"}, ` page ${page} of ${pages}`));
  return nav;
}

function show(page) {
  page = Math.min(Math.max(1, page), pages);
  const box = document.getElementById("cells");
  for (const v of box.querySelectorAll("video")) { v.removeAttribute("src"); v.load(); }
  box.replaceChildren(...rows.slice((page - 1) * pageSize, page * pageSize).map(cell));
  for (const id of ["pager-top", "pager-bottom"]) document.getElementById(id).replaceChildren(pager(page));
  document.body.dataset.page = page;
  if (location.hash !== `#page=${page}`) history.replaceState(null, "", `#page=${page}`);
}

show(parseInt((location.hash.match(/page=(\\d+)/) || [])[1] || "1", 10));
</script>
</body>
</html>
"""


def gallery_rows(out_dir: Path, results: Iterable) -> list[dict]:
    """The rows the page shows: each result's fields plus ``src``, its output relative to ``out_dir``."""
    rows = []
    for r in results:
        record = dict(vars(r)) if not isinstance(r, dict) else dict(r)
        output = Path(record["output"])
        path = output if output.is_absolute() else out_dir / output
        record["src"] = Path(os.path.relpath(path, out_dir)).as_posix()
        rows.append(record)
    return rows


def write_gallery(out_dir: str | Path, results: Iterable, *, title: str | None = None,
                  page_size: int = PAGE_SIZE) -> Path:
    """Write ``out_dir/index.html`` (atomically) for batch results (:class:`~motion2video.apps.batch.JobResult`
    or dicts with name, input, output, status, frames, seconds, error); returns its path."""
    out_dir = Path(out_dir)
    rows = gallery_rows(out_dir, results)
    data = json.dumps(rows).replace("</", "<\\/")  # cannot close the script element
    page = (_TEMPLATE.replace("__TITLE__", html.escape(title or f"motion2video batch: {out_dir.name}"))
            .replace("__PAGE_SIZE__", str(int(page_size))).replace("__ROWS__", data))
    return write_text(out_dir / INDEX_NAME, page)
