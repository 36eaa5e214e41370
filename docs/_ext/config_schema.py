"""The ``config-schema`` directive: every key of the workflow's config, from ``workflow/schemas/config.schema.yaml``.

One entry per key, in the schema's order, as Snakemake's workflow catalogue documents a config: its dotted path,
type and constraints, the schema's description, its default, and its value in the full sweep's ``config.yaml``.
Generated at build time, so the page cannot drift from the schema the workflow validates against.
"""
from pathlib import Path

import yaml
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

CONSTRAINTS = ("minimum", "maximum", "exclusiveMinimum", "minItems", "maxItems", "minLength", "pattern")


def _type(schema):
    """A short type label: ``integer``, ``list of integer``, ``one of a, b``, ``mapping``, ``string or mapping of
    a, b`` (a list item of either form)."""
    if "oneOf" in schema:
        return " or ".join(f"mapping of {', '.join(option['properties'])}" if "properties" in option else _type(option)
                           for option in schema["oneOf"])
    if "enum" in schema:
        return "one of " + ", ".join(f"``{value}``" for value in schema["enum"])
    kind = schema.get("type", "any")
    if kind == "array":
        return "list of " + _type(schema.get("items", {}))
    if kind == "object" and "properties" not in schema:
        values = schema.get("additionalProperties")
        return "mapping of name to " + (_type(values) if isinstance(values, dict) else "any")
    return {"object": "section"}.get(kind, kind)


def _constraints(schema):
    """Numeric bounds, sizes, patterns and uniqueness of a key and of its items."""
    found = [f"{name} {schema[name]!r}" if name == "pattern" else f"{name} {schema[name]}"
             for name in CONSTRAINTS if name in schema]
    if schema.get("uniqueItems"):
        found.append("unique items")
    if isinstance(schema.get("items"), dict):
        found += [f"items: {entry}" for entry in _constraints(schema["items"])]
    return found


def _lookup(config, path):
    """The value at a dotted path of ``config``, or ``None`` when it is not set (or lies under a named entry)."""
    value = config
    for part in path:
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    return value


def _keys(schema, path=(), required=()):
    """Yield ``(path, schema, required)`` for every key, depth first, in the schema's order.

    A mapping of user-named entries (``fit.experiments``) is listed as ``<name>`` with the keys of one entry.
    """
    for name, sub in schema.get("properties", {}).items():
        yield path + (name,), sub, name in required
        yield from _keys(sub, path + (name,), sub.get("required", ()))
    entries = schema.get("additionalProperties")
    if isinstance(entries, dict) and "properties" in entries:
        yield from _keys(entries, path + ("<name>",), entries.get("required", ()))


def _inline(value):
    """A YAML value on one line, as a literal."""
    text = yaml.safe_dump(value, default_flow_style=True, width=10_000).strip()
    return f"``{text.removesuffix('...').strip()}``"


def schema_rst(schema, config):
    """reStructuredText lines for every key of ``schema``, with its value in ``config``: a rubric (labelled
    ``config-<section>``) and a paragraph for each top-level section, a definition for every other key."""
    lines = []
    for path, sub, required in _keys(schema, required=schema.get("required", ())):
        dotted = ".".join(path)
        description = " ".join(sub.get("description", "").split()).replace("*", r"\*").replace("|", r"\|")
        facts = "; ".join([_type(sub) + (", required" if required else ""), *_constraints(sub)])
        body = [description[0].upper() + description[1:] + "." if description else "",
                facts[0].upper() + facts[1:] + "."]
        if "default" in sub and sub["default"] != {}:
            body.append(f"Default: {_inline(sub['default'])}.")
        value = _lookup(config, path)
        if isinstance(value, dict) and "properties" not in sub:  # user-named entries: list their names
            body.append("In ``config.yaml``: " + ", ".join(f"``{name}``" for name in value) + ".")
        elif value is not None and not isinstance(value, dict):
            body.append(f"In ``config.yaml``: {_inline(value)}.")
        body = [entry for entry in body if entry]
        if len(path) == 1 and "properties" in sub:
            lines += [f".. _config-{dotted}:", "", f".. rubric:: {dotted}", "", *body, ""]
        else:
            lines += [f"``{dotted}``", *(f"   {entry}" for entry in body), ""]
    return lines


class ConfigSchema(SphinxDirective):
    """``.. config-schema:: SCHEMA CONFIG`` (paths relative to the documentation's source folder)."""

    required_arguments = 2

    def run(self):
        source = Path(self.env.srcdir)
        schema_path, config_path = (source / argument for argument in self.arguments)
        for path in (schema_path, config_path):
            self.env.note_dependency(str(path))
        schema = yaml.safe_load(schema_path.read_text())
        config = yaml.safe_load(config_path.read_text())
        container = nodes.container()
        self.state.nested_parse(StringList(schema_rst(schema, config), source=str(schema_path)), self.content_offset,
                                container)
        return container.children


def setup(app):
    app.add_directive("config-schema", ConfigSchema)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
