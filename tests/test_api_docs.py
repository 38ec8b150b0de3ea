"""A small, documented surface (issue 37): docs/api.md is what scripts/api_docs.py writes from the docstrings;
every public callable has its numpydoc sections; every public ``__all__`` name is on the page; every other
package is internal — no ``__all__``, a docstring that says so, and only names lfproc, its tests or its scripts
use from it."""

from __future__ import annotations

import ast
import importlib
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
import api_docs  # noqa: E402

PACKAGE = ROOT / "lfproc"
INTERNAL = sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py")
                  if f"lfproc.{p.parent.name}" not in api_docs.PUBLIC_PACKAGES)


def test_docs_api_md_is_what_the_script_writes():
    assert (ROOT / "docs" / "api.md").read_text(encoding="utf-8") == api_docs.render(), \
        "docs/api.md is stale: run python scripts/api_docs.py"


@pytest.mark.parametrize("package", api_docs.PUBLIC_PACKAGES)
def test_every_public_callable_has_its_numpydoc_sections(package):
    lacking = {name: api_docs.missing_sections(getattr(importlib.import_module(package), name))
               for name in api_docs.public_names(package)}
    assert not {name: what for name, what in lacking.items() if what}


@pytest.mark.parametrize("package", api_docs.PUBLIC_PACKAGES)
def test_every_public_name_is_on_the_page(package):
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert [name for name in api_docs.public_names(package) if f"### `{package}.{name}`" not in page] == []


def test_the_checks_see_a_missing_section():
    def documented(x):
        """Twice x.

        Parameters
        ----------
        x : float

        Returns
        -------
        float
        """
        return 2 * x

    def undocumented(x):
        """Twice x."""
        return 2 * x

    class Plain:
        """A thing."""

    assert api_docs.missing_sections(documented) == []
    assert api_docs.missing_sections(undocumented) == ["Parameters", "Returns"]
    assert api_docs.missing_sections(Plain) == ["Parameters or Attributes"]


def test_the_public_packages_are_the_ones_users_are_shown():
    """The evidence for the public subpackages: the tutorial, the README and docs call them by name."""
    shown = "\n".join(p.read_text(encoding="utf-8") for p in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")]
                      if p.name != "api.md")
    for package in api_docs.PUBLIC_PACKAGES[1:]:
        assert re.search(rf"\b{re.escape(package)}\.[A-Za-z]", shown), package
    import lfproc
    assert {"geometry", "simulate"} <= set(lfproc.__all__)
    assert not {"depth", "io", "calibrate", "decode", "refocusing", "api"} & set(lfproc.__all__)


@pytest.mark.parametrize("package", INTERNAL)
def test_internal_packages_say_so_and_advertise_nothing(package):
    source = (PACKAGE / package / "__init__.py").read_text(encoding="utf-8")
    tree = ast.parse(source)
    assert "Internal package" in (ast.get_docstring(tree) or ""), package
    assert not [n for n in tree.body if isinstance(n, ast.Assign)
                and any(getattr(t, "id", None) == "__all__" for t in n.targets)], f"lfproc.{package} has an __all__"


def _texts_outside(package: str) -> str:
    paths = [*PACKAGE.rglob("*.py"), *(ROOT / "tests").rglob("*.py"), *(ROOT / "scripts").glob("*.py")]
    inside = PACKAGE / package
    return "\n".join(p.read_text(encoding="utf-8") for p in paths if inside not in p.parents)


@pytest.mark.parametrize("package", INTERNAL)
def test_internal_packages_export_only_what_is_used(package):
    """An internal ``__init__`` re-exports a name of its private modules only where something outside the package
    (lfproc's other stages, its commands, tests or scripts) uses that name."""
    tree = ast.parse((PACKAGE / package / "__init__.py").read_text(encoding="utf-8"))
    exported = [alias.asname or alias.name for node in tree.body if isinstance(node, ast.ImportFrom) and node.level
                for alias in node.names]
    outside = _texts_outside(package)
    assert [name for name in exported if not re.search(rf"\b{re.escape(name)}\b", outside)] == []
