#!/usr/bin/env python3
"""Writes the demo's index.html: the interactive viewer embedded, then every output of the demo
linked (images shown, entity and score JSON files as tables, clouds and scenes as links).
usage: demo_index.py OUT_DIR LIST    (LIST: lines "label<TAB>path", paths inside OUT_DIR or not)
"""
import html
import json
import os
import sys


def rel(path, base):
    return os.path.relpath(path, base).replace(os.sep, "/")


def scalars(value, prefix=""):
    """(key path, scalar) pairs of a JSON value, depth first."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from scalars(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(value, list):
        if all(not isinstance(v, (dict, list)) for v in value) and len(value) <= 8:
            yield prefix, ", ".join(str(v) for v in value)
        else:
            for i, v in enumerate(value):
                yield from scalars(v, f"{prefix}[{i}]")
    else:
        yield prefix, value


def json_table(path, limit=40):
    try:
        with open(path, encoding="utf-8") as f:
            document = json.load(f)
    except (OSError, ValueError) as e:
        return f"<p>cannot read: {html.escape(str(e))}</p>"
    if isinstance(document, dict) and isinstance(document.get("entities"), list):
        rows = [(e.get("id"), e.get("class"), e.get("x"), e.get("y"), e.get("z"), e.get("W"),
                 e.get("H"), e.get("L"), e.get("confidence")) for e in document["entities"]]
        head = "<tr><th>id</th><th>class</th><th>x</th><th>y</th><th>z</th><th>W</th><th>H</th>" \
               "<th>L</th><th>confidence</th></tr>"
        body = "".join("<tr>" + "".join(
            f"<td>{v:.2f}</td>" if isinstance(v, float) else f"<td>{html.escape(str(v))}</td>"
            for v in r) + "</tr>" for r in rows[:limit])
        more = f"<p>… {len(rows) - limit} more</p>" if len(rows) > limit else ""
        return f"<table>{head}{body}</table>{more}"
    pairs = list(scalars(document))
    body = "".join(f"<tr><th>{html.escape(k)}</th><td>"
                   f"{f'{v:.4g}' if isinstance(v, float) else html.escape(str(v))}</td></tr>"
                   for k, v in pairs[:limit])
    more = f"<p>… {len(pairs) - limit} more</p>" if len(pairs) > limit else ""
    return f"<table>{body}</table>{more}"


def main():
    out, listing = sys.argv[1], sys.argv[2]
    items = []
    with open(listing, encoding="utf-8") as f:
        for line in f:
            if "\t" in line:
                label, path = line.rstrip("\n").split("\t", 1)
                items.append((label, path))
    parts = []
    for label, path in items:
        href = html.escape(rel(path, out))
        name = html.escape(os.path.basename(path))
        title = f"<h3>{html.escape(label)}: <a href=\"{href}\">{name}</a></h3>"
        if path.endswith(".png"):
            parts.append(f"<figure>{title}<a href=\"{href}\"><img src=\"{href}\" alt=\"\"></a></figure>")
        elif path.endswith("index.html") and rel(path, out) != "viewer/index.html":
            parts.append(f"<figure>{title}<iframe class=\"small\" src=\"{href}\" title=\"{html.escape(label)}\"></iframe></figure>")
        elif path.endswith(".mp4"):
            parts.append(f"<figure>{title}<video src=\"{href}\" controls loop></video></figure>")
        elif path.endswith(".json"):
            parts.append(f"<details>{title and f'<summary>{title}</summary>'}{json_table(path)}</details>")
        else:
            parts.append(title)
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>stereoscene demo</title>
<link rel="icon" href="data:,">
<style>
body {{ font: 14px/1.4 system-ui, sans-serif; margin: 16px; }}
iframe {{ width: 100%; height: 70vh; border: 1px solid #999; }}
iframe.small {{ width: 960px; height: 420px; display: block; }}
figure {{ display: inline-block; margin: 8px; vertical-align: top; }}
figure img {{ max-width: 560px; border: 1px solid #ccc; }}
h3 {{ font-size: 14px; margin: 4px 0; display: inline; }}
details {{ margin: 6px 0; }}
table {{ border-collapse: collapse; font-size: 12px; }}
td, th {{ border: 1px solid #ddd; padding: 2px 6px; text-align: left; }}
</style></head><body>
<h1>stereoscene demo</h1>
<p>The analysis of the rendered street in the interactive viewer (<a href="viewer/index.html">open
alone</a>): compared with the truth and the thesis extractors, with its point cloud and the left
image.</p>
<iframe src="viewer/index.html" title="viewer"></iframe>
<h2>Outputs</h2>
{''.join(parts)}
</body></html>
"""
    with open(os.path.join(out, "index.html"), "w", encoding="utf-8") as f:
        f.write(page)


if __name__ == "__main__":
    main()
