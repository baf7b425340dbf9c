"""report.html: the report page (report.py's Markdown) as one self-contained HTML file; the verdict page of a study
(verdict_page.py) goes through the same writer (`write(..., name="verdicts.html", title=...)`).

Figures are embedded (PNG as data: URIs), movies are <video controls> pointing at the MP4 files beside the
page (relative paths: the folder can be moved or served as it is); the links from numbers to the `divcoll
export` commands of their episodes (report_episodes.py) are anchors within the page, the episode list's items
carrying the ids, and a table cell with many of them is folded into <details>. No script, no external
resource: the page renders offline. Used by report.py (`write(run, out_dir, markdown)`) and verdict_page.py.
"""
import base64
import html
import os
import re

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
# the verdict page's verdicts (verdict_page.py)
VERDICT_CSS = """
.v-supported, .v-equivalent { color: #1a7f37; } .v-contradicted { color: #c62828; }
.v-contradicted-negligible { color: #d4733a; } .v-inconclusive, .v-too-few-populations { color: #666; }
"""


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


VERDICTS = ("held", "did not hold", "too small to judge", "not measured",  # one run (the report)
            "supported", "equivalent", "contradicted (negligible)", "contradicted", "inconclusive",
            "too few populations")  # the verdict page


def verdict_class(cell):
    """the class of a table cell that is, or ends in, a verdict in bold"""
    m = re.search(r"<strong>(" + "|".join(map(re.escape, VERDICTS)) + r")</strong>( \(power [^<]*\))?$", cell.strip())
    return f' class="v-{re.sub(r"[^a-z]+", "-", m.group(1)).strip("-")}"' if m else ""


def list_item(text, out_dir):
    """a list item; one that starts with an anchor (report_episodes.py's episode list) gets it as its id"""
    m = re.match(r'<a id="([\w@.-]+)"></a>(.*)$', text)
    if m:
        return f'<li id="{m.group(1)}">{inline(m.group(2), out_dir)}</li>'
    return f"<li>{inline(text, out_dir)}</li>"


def fold(cell, most=14):
    """a table cell with more than `most` episode links, folded behind a summary that counts them"""
    n = cell.count('href="#ep-')
    if n <= most:
        return cell
    return f"<details><summary>{n} episodes</summary>{cell}</details>"


def markdown_to_html(md, out_dir):
    """the subset of Markdown report.py writes: headings, paragraphs, lists, pipe tables, inline syntax"""
    out, para, lst, rows = [], [], [], []
    toc = []

    def flush():
        if para:
            out.append("<p>" + inline(" ".join(para), out_dir) + "</p>")
            para.clear()
        if lst:
            out.append("<ul>" + "".join(list_item(x, out_dir) for x in lst) + "</ul>")
            lst.clear()
        if rows:
            cells = [[c.strip() for c in r.strip().strip("|").split("|")] for r in rows]
            body = [c for c in cells[1:] if not all(re.fullmatch(r":?-+:?", x) for x in c)]
            t = ['<div class="wide"><table><thead><tr>' + "".join(f"<th>{inline(c, out_dir)}</th>" for c in cells[0]) + "</tr></thead><tbody>"]
            for r in body:
                t.append("<tr>" + "".join(f"<td{verdict_class(inline(c, out_dir))}>{fold(inline(c, out_dir))}</td>"
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


def write(run, out_dir, md, name="report.html", title=None, css=CSS):
    """out_dir/name: the page of Markdown `md` (figures it names relative to out_dir); title default 'divcoll report:
    RUN'"""
    body, toc = markdown_to_html(md, out_dir)
    nav = "<nav><strong>Contents</strong>: " + " · ".join(
        f'<a href="#{a}">{inline(t, out_dir)}</a>' for a, t in toc) + "</nav>"
    title = html.escape(title or f"divcoll report: {os.path.basename(run)}")
    k = 1 if body and body[0].startswith("<h1") else 0
    page = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{title}</title><style>{css}</style></head><body>", *body[:k], nav, *body[k:], "</body></html>"]
    path = os.path.join(out_dir, name)
    with open(path, "w") as fh:
        fh.write("\n".join(page) + "\n")
    return path
