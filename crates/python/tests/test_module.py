"""The installed package: the abi3 extension, its type stubs and py.typed, and a docstring
for everything the stubs promise."""

import ast
from pathlib import Path

import aperture


def test_the_wheel_ships_stubs_and_py_typed():
    package = Path(aperture.__file__).parent
    names = {p.name for p in package.iterdir()}
    assert "py.typed" in names
    assert any(n.endswith(".pyi") for n in names), names
    assert any(n.endswith(".abi3.so") for n in names), names


def test_every_stubbed_name_exists_and_is_documented():
    stub = Path(aperture.__file__).parent / "__init__.pyi"
    tree = ast.parse(stub.read_text())
    checked = 0
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            assert getattr(aperture, node.name).__doc__, node.name
            checked += 1
        typed_dicts = ("Hits", "CameraRays", "Triangles", "Primitive")  # the stub's own
        if isinstance(node, ast.ClassDef) and node.name not in typed_dicts:
            cls = getattr(aperture, node.name)
            assert cls.__doc__, node.name
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and not item.name.startswith("__"):
                    assert getattr(cls, item.name).__doc__, f"{node.name}.{item.name}"
                    checked += 1
    assert checked >= 15
    assert isinstance(aperture.__version__, str)
