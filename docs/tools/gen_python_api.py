"""Write the Python API reference (Markdown) from python/irtp/__init__.pyi.

Every public class and function of the type stubs, in the stubs' order,
with its signature as the stubs write it, the comment above it and its
docstring. Defaults are `...` in the stubs: they are the CLI's (the
command reference has them).

    python docs/tools/gen_python_api.py python/irtp/__init__.pyi OUT.md
"""

import ast
import sys


def comment_above(lines, lineno):
    """The `#` comment lines directly above 1-based line `lineno`."""
    out, i = [], lineno - 2
    while i >= 0 and lines[i].lstrip().startswith("#"):
        out.insert(0, lines[i].lstrip()[1:].strip())
        i -= 1
    return " ".join(out)


def main():
    stub, out = sys.argv[1], sys.argv[2]
    source = open(stub).read()
    lines = source.splitlines()
    tree = ast.parse(source)
    md = [
        "# Python API",
        "",
        "Generated when the docs are built from the type stubs",
        "`python/irtp/__init__.pyi`: every public class and function with its",
        "signature. Keyword arguments are the CLI's flags (`--t-max` becomes",
        "`t_max`; `lambda_`, `from_`), with the CLI's defaults: see the",
        "[command reference](cli.md). How to use them: [Python](../python.md).",
        "",
    ]
    count = 0
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            continue
        if node.name.startswith("_"):
            continue
        kind = "class" if isinstance(node, ast.ClassDef) else "function"
        md += [f"## `{node.name}` ({kind})", ""]
        note = comment_above(lines, node.lineno - len(node.decorator_list))
        if note:
            md += [note, ""]
        doc = ast.get_docstring(node)
        if doc:
            md += [doc, ""]
        md += ["```python", ast.get_source_segment(source, node), "```", ""]
        count += 1
    with open(out, "w") as f:
        f.write("\n".join(md))
    print(f"gen_python_api: {count} items -> {out}")


if __name__ == "__main__":
    main()
