"""report.html: the report page (report.py's Markdown) as one self-contained HTML file.

Figures are embedded (PNG as data: URIs), movies are <video controls> pointing at the MP4 files beside the
page (relative paths: the folder can be moved or served as it is), and a table of Fig. 2A's numbers per
environment and collective type links every number to the `divcoll export` command of its episode (the
median ok episode of that cell, replicate 0) and of the agent alone behind the "agents" column. No script,
no external resource: the page renders offline. Used by report.py (`write(run, out_dir, markdown)`).
"""
import base64
import html
import os
import re

import h5py
import numpy as np

CSS = """
body { font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; max-width: 1180px; margin: 1em auto;
       padding: 0 1em; color: #222; line-height: 1.45; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em; font-size: 0.88em; }
th, td { border: 1px solid #ccc; padding: 3px 7px; vertical-align: top; }
th { background: #f2f2f2; }
code { background: #f5f5f5; padding: 0 3px; font-size: 0.92em; }
img, video { max-width: 100%; border: 1px solid #ddd; }
nav { background: #fafafa; border: 1px solid #e3e3e3; padding: 0.4em 1em; }
.v-held { color: #1a7f37; } .v-did-not-hold { color: #c62828; }
.v-too-small-to-judge { color: #8a6d00; } .v-not-measured { color: #666; }
td.num a { text-decoration: none; }
.wide { overflow-x: auto; }
li:target, code:target { background: #fff3b0; }
"""


def _s(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def inline(text, out_dir):
    """Markdown inline syntax of the report: code, bold, italics, links, images"""
    codes = []

    def keep(m):
        codes.append(f"<code>{html.escape(m.group(1))}</code>")
        return f"\x00{len(codes) - 1}\x00"

    p = re.sub(r"`([^`]*)`", keep, text)
    p = html.escape(p, quote=False)
    p = re.sub(r"!\[([^\]]*)\]\(([^)]+)\)", lambda m: image(m.group(2), m.group(1), out_dir), p)
    p = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", lambda m: link(m.group(1), m.group(2), out_dir), p)
    p = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", p)
    p = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<em>\1</em>", p)
    return re.sub(r"\x00(\d+)\x00", lambda m: codes[int(m.group(1))], p)


def image(src, alt, out_dir):
    path = os.path.join(out_dir, src)
    if src.endswith(".png") and os.path.isfile(path):
        with open(path, "rb") as fh:
            data = base64.b64encode(fh.read()).decode()
        return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'
    return f'<img alt="{html.escape(alt)}" src="{html.escape(src)}">'


def link(text, href, out_dir):
    if href.endswith(".mp4"):
        return (f'<figure><video controls preload="metadata" width="1280" src="{html.escape(href)}"></video>'
                f'<figcaption>{text} (<a href="{html.escape(href)}">download</a>)</figcaption></figure>')
    return f'<a href="{html.escape(href)}">{text}</a>'


def verdict_class(cell):
    m = re.fullmatch(r"<strong>(held|did not hold|too small to judge|not measured)</strong>", cell.strip())
    return f' class="v-{m.group(1).replace(" ", "-")}"' if m else ""


def markdown_to_html(md, out_dir):
    """the subset of Markdown report.py writes: headings, paragraphs, lists, pipe tables, inline syntax"""
    out, para, lst, rows = [], [], [], []
    toc = []

    def flush():
        if para:
            out.append("<p>" + inline(" ".join(para), out_dir) + "</p>")
            para.clear()
        if lst:
            out.append("<ul>" + "".join(f"<li>{inline(x, out_dir)}</li>" for x in lst) + "</ul>")
            lst.clear()
        if rows:
            cells = [[c.strip() for c in r.strip().strip("|").split("|")] for r in rows]
            body = [c for c in cells[1:] if not all(re.fullmatch(r":?-+:?", x) for x in c)]
            t = ['<div class="wide"><table><thead><tr>' + "".join(f"<th>{inline(c, out_dir)}</th>" for c in cells[0]) + "</tr></thead><tbody>"]
            for r in body:
                t.append("<tr>" + "".join(f"<td{verdict_class(inline(c, out_dir))}>{inline(c, out_dir)}</td>"
                                          for c in r) + "</tr>")
            out.append("".join(t) + "</tbody></table></div>")
            rows.clear()

    for line in md.splitlines():
        m = re.match(r"^(#{1,4}) (.*)$", line)
        if m:
            flush()
            level, title = len(m.group(1)), m.group(2)
            anchor = re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")
            if level == 2:
                toc.append((anchor, title))
            out.append(f'<h{level} id="{anchor}">{inline(title, out_dir)}</h{level}>')
        elif line.startswith("|"):
            if para or lst:
                flush()
            rows.append(line)
        elif re.match(r"^\s*- ", line):
            if para or rows:
                flush()
            lst.append(re.sub(r"^\s*- ", "", line))
        elif not line.strip():
            flush()
        else:
            if rows:
                flush()
            para.append(line.strip())
    flush()
    return out, toc


def episode_table(run, run_arg):
    """Fig. 2A per environment, every number linked to the export command of its episode (HTML lines)"""
    with h5py.File(run, "r") as f:
        if "deploy" not in f or "deploy/collectives/travel_bl" not in f:
            return []
        d = f["deploy"]
        envs = _s(d.attrs["environments"]).split(",")
        types = _s(d.attrs["types"]).split(",")
        ct, cs = d["collectives/travel_bl"][()], d["collectives/status"][()]
        at, ast = d["agents/travel_bl"][()], d["agents/status"][()]
    done = min(len(envs), ct.shape[0])
    head = ["<h2 id=\"numbers-and-their-episodes\">Fig. 2A per environment: numbers and their episodes</h2>",
            "<p>Each number is the mean travel (BL) over the ok episodes of its cell; it links to the "
            "<code>divcoll export</code> command of the cell's median ok episode (replicate 0 for collectives), "
            "whose scene <code>divcoll simulate</code> turns back into that episode's travel bit for bit.</p>",
            '<div class="wide"><table><thead><tr><th>environment</th><th>agents alone</th>'
            + "".join(f"<th>{html.escape(t)}</th>" for t in types) + "</tr></thead><tbody>"]
    cmds = []
    for e in range(done):
        env = envs[e]
        cells = []
        ok = (ast[e] == 0) & np.isfinite(at[e])
        if ok.any():
            vals = at[e][ok]
            idx = np.flatnonzero(ok)[np.argsort(vals)[(len(vals) - 1) // 2]]
            aid = f"ep-{env}-alone"
            cmds.append((aid, f"divcoll export {run_arg} --what alone --env {env} --agent {idx} --out {env}_agent{idx}.h5",
                         f"agent {idx} alone in {env}: {at[e][idx]:.3f} BL"))
            cells.append(f'<td class="num"><a href="#{aid}">{vals.mean():.3f}</a></td>')
        else:
            cells.append("<td>—</td>")
        for t, typ in enumerate(types):
            v, s = ct[e, t], cs[e, t]
            ok = (s == 0) & np.isfinite(v)
            if not ok.any():
                cells.append("<td>—</td>")
                continue
            r0 = (s[0] == 0) & np.isfinite(v[0])
            mean = v[ok].mean()
            if r0.any():
                q = np.flatnonzero(r0)[np.argsort(v[0][r0])[(int(r0.sum()) - 1) // 2]]
                cid = f"ep-{env}-{typ.replace('@', '-at-')}"
                cmds.append((cid, f"divcoll export {run_arg} --what pair --env {env} --type {typ} --replicate 0 "
                                  f"--pair {q} --out {env}_{typ.replace('@', '_at_')}_p{q}.h5",
                             f"{typ} replicate 0 pair {q} in {env}: {v[0][q]:.3f} BL"))
                cells.append(f'<td class="num"><a href="#{cid}">{mean:.3f}</a></td>')
            else:
                cells.append(f"<td>{mean:.3f}</td>")
        head.append(f"<tr><td>{html.escape(env)}</td>" + "".join(cells) + "</tr>")
    head.append("</tbody></table></div><details open><summary>the episodes behind the numbers</summary><ul>")
    for cid, cmd, what in cmds:
        head.append(f'<li id="{cid}">{html.escape(what)}: <code>{html.escape(cmd)}</code></li>')
    head.append("</ul></details>")
    return head


def write(run, out_dir, md):
    body, toc = markdown_to_html(md, out_dir)
    numbers = episode_table(run, os.path.abspath(run))
    if numbers:
        toc.insert(2, ("numbers-and-their-episodes", "Fig. 2A per environment: numbers and their episodes"))
        # after the claims table
        k = next((i for i, b in enumerate(body) if 'id="stages-and-numbers"' in b), len(body))
        body = body[:k] + numbers + body[k:]
    nav = "<nav><strong>Contents</strong>: " + " · ".join(
        f'<a href="#{a}">{inline(t, out_dir)}</a>' for a, t in toc) + "</nav>"
    title = html.escape(f"divcoll report: {os.path.basename(run)}")
    k = 1 if body and body[0].startswith("<h1") else 0
    page = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{title}</title><style>{CSS}</style></head><body>", *body[:k], nav, *body[k:], "</body></html>"]
    path = os.path.join(out_dir, "report.html")
    with open(path, "w") as fh:
        fh.write("\n".join(page) + "\n")
    return path
