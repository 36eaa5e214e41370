"""A report as a list of blocks, rendered to Markdown (figures linked) and to self-contained HTML (figures
embedded as base64 PNG data URIs, inline CSS, no network).

Blocks are tuples: ``("h1", text)``, ``("h2", text, anchor)``, ``("h3", text, anchor)``, ``("p", text)``, ``("list", [text, ...])`` or
``("list", [text, ...], [anchor, ...])``, ``("table", header, rows)`` and ``("figure", name, caption)`` with ``name``
a PNG in ``figures/``. Text is plain (escaped in HTML) with three kinds of markup: ``**bold**``, links to an
anchor of the page ``[text](#anchor)`` and verdict badges ``{{verdict}}`` (a coloured label in HTML, a coloured
mark in Markdown). Anchors are HTML ids (``<a id>`` in Markdown).
"""
import base64
import html
import re

CSS = """body{font-family:sans-serif;max-width:62rem;margin:2rem auto;padding:0 1rem;line-height:1.45;color:#222}
table{border-collapse:collapse;margin:.8rem 0}td,th{border:1px solid #bbb;padding:.25rem .5rem;text-align:right}
td:first-child,th:first-child{text-align:left}figure{margin:1rem 0}img{max-width:100%}
figcaption{font-size:.9rem;color:#444}li{margin:.4rem 0}h1{margin:.5rem 0}
table.summary{font-size:.8rem;line-height:1.25}table.summary td{vertical-align:top}
table.summary td,table.summary th{text-align:left}
.badge{display:inline-block;padding:.1rem .45rem;border-radius:.7rem;color:#fff;font-weight:bold;white-space:nowrap}
.reproduced{background:#1a7f37}.partly{background:#bf8700}.not-reproduced{background:#cf222e}
.pending{background:#6e7781}.within-timing-noise{background:#8250df}.inconclusive{background:#0969da}"""

BADGE_MARKS = {"reproduced": "🟢", "partly": "🟡", "not reproduced": "🔴", "inconclusive": "🔵",
               "within timing noise": "🟣", "pending": "⚪"}
"""Verdict -> the coloured mark beside its badge in Markdown (HTML colours it with CSS)."""

_LINK = re.compile(r"\[([^\]]+)\]\(#([\w-]+)\)")
_BADGE = re.compile(r"\{\{([a-z ]+)\}\}")


def _bold_html(text):
    """Text as HTML with its markup: bold, links to anchors and verdict badges."""
    text = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", html.escape(text, quote=False))
    text = _LINK.sub(r'<a href="#\2">\1</a>', text)
    return _BADGE.sub(lambda m: f'<span class="badge {m[1].replace(" ", "-")}">{m[1]}</span>', text)


def _markdown_text(text):
    """Text as Markdown: badges become a coloured mark and the verdict in bold."""
    return _BADGE.sub(lambda m: f"{BADGE_MARKS.get(m[1], '')} **{m[1]}**", text)


def markdown_table(header, rows):
    """A GitHub-flavoured Markdown table of strings (no final newline); a newline in a cell becomes ``<br>``."""
    def line(cells):
        return "| " + " | ".join(cell.replace("|", "\\|").replace("\n", "<br>") for cell in cells) + " |"

    return "\n".join([line(header), "|" + "|".join(["---"] * len(header)) + "|"] + [line(row) for row in rows])


def _anchor(anchor):
    return f'<a id="{anchor}"></a>' if anchor else ""


MARKDOWN = {
    "h1": lambda text: f"# {text}",
    "h2": lambda text, anchor=None: f"## {_anchor(anchor)}{text}",
    "h3": lambda text, anchor=None: f"### {_anchor(anchor)}{text}",
    "p": lambda text: text,
    "list": lambda items, anchors=None: "\n".join(f"- {_anchor(anchor)}{item}"
                                                  for item, anchor in zip(items, anchors or [None] * len(items))),
    "table": lambda header, rows, css_class=None: markdown_table(header, rows),
    "figure": lambda name, caption: f"![{name}](figures/{name}.png)\n\n*{caption}*",
}


def to_markdown(blocks):
    """The report as Markdown; figures are linked as ``figures/{name}.png``."""
    return _markdown_text("\n\n".join(MARKDOWN[kind](*args) for kind, *args in blocks)) + "\n"


def _html_table(header, rows, css_class=None):
    def cell(text):
        return _bold_html(text).replace("\n", "<br>")

    head = "".join(f"<th>{cell(text)}</th>" for text in header)
    body = "".join("<tr>" + "".join(f"<td>{cell(text)}</td>" for text in row) + "</tr>" for row in rows)
    attribute = f' class="{css_class}"' if css_class else ""
    return f"<table{attribute}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _id(anchor):
    return f' id="{anchor}"' if anchor else ""


def to_html(blocks, images, title):
    """The report as one self-contained HTML page.

    Parameters
    ----------
    blocks : list of tuple
    images : dict
        ``name -> PNG bytes`` of every figure block.
    title : str
    """
    def figure(name, caption):
        data = base64.b64encode(images[name]).decode("ascii")
        return (f'<figure><img src="data:image/png;base64,{data}" alt="{name}">'
                f"<figcaption>{_bold_html(caption)}</figcaption></figure>")

    render = {
        "h1": lambda text: f"<h1>{_bold_html(text)}</h1>",
        "h2": lambda text, anchor=None: f"<h2{_id(anchor)}>{_bold_html(text)}</h2>",
        "h3": lambda text, anchor=None: f"<h3{_id(anchor)}>{_bold_html(text)}</h3>",
        "p": lambda text: f"<p>{_bold_html(text)}</p>",
        "list": lambda items, anchors=None: "<ul>" + "".join(
            f"<li{_id(anchor)}>{_bold_html(item)}</li>" for item, anchor in zip(items, anchors or [None] * len(items)))
            + "</ul>",
        "table": _html_table,
        "figure": figure,
    }
    body = "\n".join(render[kind](*args) for kind, *args in blocks)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{CSS}</style></head><body>\n{body}\n</body></html>\n")
