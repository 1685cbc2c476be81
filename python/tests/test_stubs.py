"""The type stubs of the extension name what it has, and the package ships
them (PEP 561)."""

from __future__ import annotations

import ast
from pathlib import Path

import railmbs
from railmbs import _railmbs


def test_stubs_match_the_extension():
    pkg = Path(railmbs.__file__).parent
    assert (pkg / "py.typed").exists()
    tree = ast.parse((pkg / "_railmbs.pyi").read_text())
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            cls = getattr(_railmbs, node.name)
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and item.name != "__init__":
                    assert hasattr(cls, item.name), f"{node.name}.{item.name}"
            # Every public method of the class is in the stub.
            stubbed = {i.name for i in node.body if isinstance(i, ast.FunctionDef)}
            public = {n for n in dir(cls) if not n.startswith("__")}
            assert public <= stubbed, f"{node.name}: not in the stub: {public - stubbed}"
        elif isinstance(node, ast.FunctionDef):
            assert hasattr(_railmbs, node.name), node.name
    # Docstrings with units reach help().
    assert "s" in railmbs.Scenario.run.__doc__ and "GIL" in railmbs.Scenario.run.__doc__
    assert "N" in railmbs.contact.creep_forces.__doc__
