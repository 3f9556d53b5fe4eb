"""MkDocs hooks: the reference pages made from the code, so they cannot drift from it.

- ``reference/components/``: one page per library and an index, from each component type's
  declarations (``Component.reference()``: summary, signature, parameters with unit, default
  and bounds, ports with their domain and what a probe wired there records);
- ``reference/cli.md``'s command list: from the ``kinetwork`` command's argparse parser.
"""

import argparse
import html
import pathlib
import re

from mkdocs.structure.files import File

import kinetwork as kn
from kinetwork.cli import build_parser
from kinetwork.components.base import REGISTRY
from kinetwork.components.reference import reference

DOMAIN_WORDS = {"frame": "frame (3-D)", "rotational": "rotational flange",
                "translational": "translational flange", "signal_in": "signal input",
                "signal_out": "signal output", "electrical": "electrical pin"}


ROOT = pathlib.Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench" / "results"


def on_files(files, config):
    for path, text in _component_pages().items():
        files.append(File.generated(config, f"reference/components/{path}", content=text))
    for image in sorted(BENCH.glob("*.png")):
        files.append(File.generated(config, f"bench/{image.name}", abs_src_path=str(image)))
    return files


def on_page_markdown(markdown, page, config, files):
    if page.file.src_uri == "reference/cli.md":
        return markdown.replace("{{ cli_commands }}", _cli_page())
    if page.file.src_uri == "bench.md":
        return markdown.replace("{{ bench_summary }}", _bench_summary())
    return markdown


def _bench_summary():
    """bench/results/summary.md one heading level down, its charts linked where they exist
    (a chart the last run did not write is left out, not linked broken)."""
    text = (BENCH / "summary.md").read_text()
    text = text.split("\n", 1)[1] if text.startswith("# ") else text

    def image(match):
        name = match.group(2)
        return f"![{match.group(1)}](bench/{name})" if (BENCH / name).is_file() else ""
    text = re.sub(r"!\[([^\]]*)\]\(([^)/]+\.png)\)", image, text)
    # a study's link to another results file: that file's section is on this page too
    text = re.sub(r"(?<!!)\[([^\]]*)\]\(([^)/]+\.md)\)", r"`\2`", text)
    return re.sub(r"^(#+) ", lambda m: "#" + m.group(1) + " ", text, flags=re.M)


# -- components -----------------------------------------------------------------------------
def _libraries():
    out = {}
    for type_name in sorted(REGISTRY, key=lambda t: (t.count("."), t)):
        library = type_name.rsplit(".", 1)[0] if "." in type_name else "core"
        out.setdefault(library, []).append(type_name)
    return out


def _component_pages():
    libraries = _libraries()
    index = ["# Components", "",
             "Every component type a model can place, by library: its parameters (unit, "
             "default, bounds), its ports (domain) and what a probe wired to each port "
             "records. The same declarations give `help(kn.multibody.RigidBody)`, the "
             "JSON Schema's descriptions and the studio's palette. Numbers may carry units "
             "(`\"2 kg\"`, `\"30 deg\"`): see [units](../../how-to/files.md#units).", ""]
    pages = {}
    for library, types in libraries.items():
        index.append(f"## [{library}]({library}.md)")
        index.append("")
        index.append("| type | what it is |")
        index.append("| --- | --- |")
        body = [f"# {library}", ""]
        for type_name in types:
            ref = reference(REGISTRY[type_name])
            short = type_name.rsplit(".", 1)[-1]
            anchor = short.lower()
            summary = _paragraphs(REGISTRY[type_name])[0]
            index.append(f"| [`{type_name}`]({library}.md#{anchor}) | {_cell(summary)} |")
            body += _component(type_name, short, ref, REGISTRY[type_name])
        index.append("")
        pages[f"{library}.md"] = "\n".join(body)
    pages["index.md"] = "\n".join(index)
    return pages


def _component(type_name, short, ref, cls):
    summary, description = _paragraphs(cls)
    lines = [f"## {short}", "", f"`{type_name}`: {_text(summary)}", ""]
    if description:
        lines += [_text(description), ""]
    lines += ["```python", _signature(ref["signature"]), "```", ""]
    params = ref.get("params") or []
    if params:
        lines += ["| parameter | unit | default | bounds | meaning |",
                  "| --- | --- | --- | --- | --- |"]
        for p in params:
            unit = p["unit"] if not isinstance(p["unit"], list) else ", ".join(p["unit"])
            default = "required" if p["required"] else _value(p["default"])
            lines.append(f"| `{p['name']}` | {_cell(unit) or '–'} | {_cell(default)} | "
                         f"{_bounds(p)} | {_cell(p['doc'])} |")
        lines.append("")
    ports = ref.get("ports") or []
    if ports:
        lines += ["| port | domain | meaning | a probe here records |",
                  "| --- | --- | --- | --- |"]
        for port in ports:
            quantities = ", ".join(f"{q['name']} [{q['unit'] or '1'}]"
                                   for q in port.get("quantities") or [])
            doc = port["doc"] + (" (optional)" if port.get("optional") else "")
            lines.append(f"| `{port['name']}` | {DOMAIN_WORDS.get(port['domain'], port['domain'])}"
                         f" | {_cell(doc)} | {_cell(quantities) or '–'} |")
        lines.append("")
    return lines


def _paragraphs(cls):
    """The summary (the docstring's first paragraph, on one line) and the rest, without a
    numpydoc Parameters section (the table says it)."""
    doc = (cls._own_doc or "").strip()
    doc = re.split(r"^Parameters\n-{3,}", doc, flags=re.M)[0].strip()
    head, _, rest = doc.partition("\n\n")
    return " ".join(head.split()), rest.strip()


def _text(text):
    """Docstring prose as Markdown: ``code`` kept, ``*`` and ``_`` outside it literal."""
    parts = re.split(r"(``?[^`]+``?)", text)
    out = []
    for part in parts:
        if part.startswith("`"):
            out.append("`" + part.strip("`") + "`")
        else:
            out.append(re.sub(r"([*_\\<>])", r"\\\1", part))
    return "".join(out)


def _signature(text, width=88):
    """One parameter per line when the signature is longer than a line."""
    if len(text) <= width:
        return text
    name, _, params = text.partition("(")
    params = params[:-1]
    items, depth, current = [], 0, ""
    for ch in params:
        if ch == "," and depth == 0:
            items.append(current.strip())
            current = ""
            continue
        depth += ch in "([{"
        depth -= ch in ")]}"
        current += ch
    items.append(current.strip())
    return name + "(\n" + "".join(f"    {item},\n" for item in items) + ")"


def _bounds(p):
    parts = []
    if p.get("min") is not None:
        parts.append(f"≥ {p['min']:g}")
    if p.get("max") is not None:
        parts.append(f"≤ {p['max']:g}")
    if p.get("positive"):
        parts.append("> 0")
    if p.get("nonzero"):
        parts.append("≠ 0")
    if p.get("choices"):
        parts.append(" / ".join(f"`{c}`" for c in p["choices"]))
    return ", ".join(parts) or "–"


def _value(value):
    if value is None:
        return "none"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, str):
        return f"`{value}`"
    return f"`{value}`"


def _cell(text):
    return html.escape(str(text or ""), quote=False).replace("|", "\\|").replace("\n", " ")


# -- command line ---------------------------------------------------------------------------
def _cli_page():
    parser = build_parser()
    lines = []
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, command in sub.choices.items():
        lines += [f"### kinetwork {name}", "", command.description or "", "", "```text",
                  command.format_usage().strip(), "```", ""]
        rows = [a for a in command._actions if a.option_strings and a.dest != "help"]
        if rows:
            lines += ["| option | meaning |", "| --- | --- |"]
            for a in rows:
                lines.append(f"| `{', '.join(a.option_strings)}` | {_cell(a.help)} |")
            lines.append("")
    return "\n".join(lines)


__all__ = ["on_files", "on_page_markdown", "kn"]
