"""A report as a list of blocks, rendered to Markdown (figures linked) and to self-contained HTML (figures
embedded as base64 PNG data URIs, inline CSS, no network).

Blocks are tuples: ``("h1" | "h2", text)``, ``("p", text)``, ``("list", [text, ...])``,
``("table", header, rows)`` and ``("figure", name, caption)`` with ``name`` a PNG in ``figures/``. Text is plain
(escaped in HTML); ``**bold**`` spans are the only markup.
"""
import base64
import html
import re

CSS = """body{font-family:sans-serif;max-width:62rem;margin:2rem auto;padding:0 1rem;line-height:1.45;color:#222}
table{border-collapse:collapse;margin:.8rem 0}td,th{border:1px solid #bbb;padding:.25rem .5rem;text-align:right}
td:first-child,th:first-child{text-align:left}figure{margin:1rem 0}img{max-width:100%}
figcaption{font-size:.9rem;color:#444}li{margin:.4rem 0}"""


def _bold_html(text):
    return re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", html.escape(text, quote=False))


def markdown_table(header, rows):
    """A GitHub-flavoured Markdown table of strings (no final newline)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(["---"] * len(header)) + "|"]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


MARKDOWN = {
    "h1": lambda text: f"# {text}",
    "h2": lambda text: f"## {text}",
    "p": lambda text: text,
    "list": lambda items: "\n".join(f"- {item}" for item in items),
    "table": markdown_table,
    "figure": lambda name, caption: f"![{name}](figures/{name}.png)\n\n*{caption}*",
}


def to_markdown(blocks):
    """The report as Markdown; figures are linked as ``figures/{name}.png``."""
    return "\n\n".join(MARKDOWN[kind](*args) for kind, *args in blocks) + "\n"


def _html_table(header, rows):
    head = "".join(f"<th>{_bold_html(cell)}</th>" for cell in header)
    body = "".join("<tr>" + "".join(f"<td>{_bold_html(cell)}</td>" for cell in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


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
        return (f'<figure id="{name}"><img src="data:image/png;base64,{data}" alt="{name}">'
                f"<figcaption>{_bold_html(caption)}</figcaption></figure>")

    render = {
        "h1": lambda text: f"<h1>{_bold_html(text)}</h1>",
        "h2": lambda text: f"<h2>{_bold_html(text)}</h2>",
        "p": lambda text: f"<p>{_bold_html(text)}</p>",
        "list": lambda items: "<ul>" + "".join(f"<li>{_bold_html(item)}</li>" for item in items) + "</ul>",
        "table": _html_table,
        "figure": figure,
    }
    body = "\n".join(render[kind](*args) for kind, *args in blocks)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{CSS}</style></head><body>\n{body}\n</body></html>\n")
