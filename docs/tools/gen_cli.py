"""Write the command reference (Markdown) from the `irtp` binary's own help.

Walks `irtp --help` and, recursively, every subcommand its "Commands:"
section lists, so every command and flag of the page is the CLI
definition's text (clap's long help), never a copy.

    python docs/tools/gen_cli.py IRTP_BIN OUT.md
"""

import subprocess
import sys


def help_text(binary, path):
    out = subprocess.run(
        [binary, *path, "--help"], capture_output=True, text=True, check=True
    )
    return out.stdout


def subcommands(text):
    """The names listed under the help's "Commands:" heading ("help" left out)."""
    names, inside = [], False
    for line in text.splitlines():
        if line.strip() == "Commands:":
            inside = True
            continue
        if inside:
            if not line.startswith("  ") or not line.strip():
                break
            name = line.split()[0]
            if name != "help":
                names.append(name)
    return names


def walk(binary, path=()):
    text = help_text(binary, list(path))
    yield path, text
    for name in subcommands(text):
        yield from walk(binary, (*path, name))


def main():
    binary, out = sys.argv[1], sys.argv[2]
    version = subprocess.run(
        [binary, "--version"], capture_output=True, text=True, check=True
    ).stdout.strip()
    pages = list(walk(binary))
    lines = [
        "# Command reference",
        "",
        f"Generated when the docs are built from `{version}`: each section is that",
        "command's `--help` as the binary prints it (clap's long help), so it",
        "cannot drift from the code. Conventions shared by every command (refusals,",
        "budgets, exit codes) are in [Flags, refusals, budgets and exit codes](conventions.md).",
        "",
        "Commands: " + ", ".join(f"[`{' '.join(('irtp', *p))}`](#{anchor(p)})" for p, _ in pages),
        "",
    ]
    for path, text in pages:
        lines += [f"## {' '.join(('irtp', *path))} {{#{anchor(path)}}}", "", "```text"]
        lines += [text.rstrip("\n"), "```", ""]
    with open(out, "w") as f:
        f.write("\n".join(lines))
    print(f"gen_cli: {len(pages)} commands -> {out}")


def anchor(path):
    return "-".join(("irtp", *path))


if __name__ == "__main__":
    main()
