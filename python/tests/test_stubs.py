"""The type stubs list the same keywords, in the same order, as the runtime
signatures built from the CLI definitions."""

from __future__ import annotations

import ast
import inspect
import pathlib

import irtp

STUB = pathlib.Path(irtp.__file__).with_name("__init__.pyi")


def stub_functions():
    tree = ast.parse(STUB.read_text())
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}


def test_stub_and_py_typed_ship_with_the_package():
    assert STUB.exists()
    assert STUB.with_name("py.typed").exists()


def test_stub_signatures_match_runtime():
    stubs = stub_functions()
    for name in irtp._api.COMMANDS:
        node = stubs[name]
        stub_kw = [a.arg for a in node.args.kwonlyargs]
        sig = inspect.signature(getattr(irtp, name))
        runtime_kw = [p.name for p in sig.parameters.values() if p.kind == p.KEYWORD_ONLY]
        assert stub_kw == runtime_kw, name
        required = {p.name for p in sig.parameters.values()
                    if p.kind == p.KEYWORD_ONLY and p.default is p.empty}
        stub_required = {a.arg for a, d in zip(node.args.kwonlyargs, node.args.kw_defaults)
                         if d is None}
        assert stub_required == required, name
        if node.args.vararg is not None:
            assert any(p.kind == p.VAR_POSITIONAL for p in sig.parameters.values())


def test_stub_declares_every_public_name():
    tree = ast.parse(STUB.read_text())
    declared = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    declared |= {t.target.id for t in tree.body
                 if isinstance(t, ast.AnnAssign) and isinstance(t.target, ast.Name)}
    assert set(irtp.__all__) <= declared
