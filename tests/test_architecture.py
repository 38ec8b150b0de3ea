"""The architecture of docs/architecture.md, checked against the code.

* the import-linter contracts of ``pyproject.toml`` (layers, no cycles between stages, a light core, computing
  stages without files, each stage's private modules private) are kept: ``lint-imports`` passes;
* every stage folder has its "private modules" contract, so a new stage cannot slip past it;
* no module imports another stage's private module (an AST scan, independent of import-linter);
* the "may import" column of docs/architecture.md's table is exactly what each folder imports;
* the modules that read or write files are the ones the page names;
* modules stay under ~400 lines (the known exceptions are listed, with why).
"""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "lfproc"
DOC = ROOT / "docs" / "architecture.md"

# modules being rewritten under issue 31 by others (decoder, Python API); remove each once it is split
LONG_MODULES_BEING_REWRITTEN: set = set()
MAX_LINES = 400


def _modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the package."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _imports(name: str, path: Path) -> list[tuple[str, int]]:
    """Absolute names of the lfproc modules (or module attributes) ``name`` imports, anywhere in the file, with
    their lines; ``from X import y`` yields ``X.y`` (``y`` may be a module or a name in ``X``)."""
    is_package = path.name == "__init__.py"
    here = name.split(".") if is_package else name.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names if alias.name.split(".")[0] == "lfproc"]
        elif isinstance(node, ast.ImportFrom):
            base = (here[:len(here) - node.level + 1] if node.level else []) + (node.module or "").split(".")
            base = [part for part in base if part]
            if base and base[0] == "lfproc":
                found += [(".".join(base + [alias.name]), node.lineno) for alias in node.names]
    return found


def _stage(module: str) -> str:
    """The top-level folder or module of ``lfproc.X...`` ("lfproc" for the package itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "lfproc"


def test_import_contracts_are_kept():
    """``lint-imports`` (import-linter, configured in pyproject.toml) passes on the package."""
    pytest.importorskip("importlinter", reason="import-linter is in the test extra: pip install -e .[test]")
    code = ("import sys; from importlinter.cli import lint_imports; "
            "sys.exit(lint_imports(config_filename='pyproject.toml', no_cache=True, no_logo=True))")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-2000:]
    assert "0 broken" in run.stdout


def test_every_stage_folder_has_its_private_modules_contract():
    try:
        import tomllib
    except ModuleNotFoundError:          # Python 3.10
        import tomli as tomllib
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]
    protected = {tuple(c["protected_modules"]): tuple(c["allowed_importers"])
                 for c in config["contracts"] if c["type"] == "protected"}
    stages = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists() and p.name != "cli")
    assert stages, "no stage folders found"
    for stage in stages:
        assert protected.get((f"lfproc.{stage}.*",)) == (f"lfproc.{stage}",), \
            f"{stage}/ has no 'protected' contract for its private modules in pyproject.toml"
    # cli/ is the only folder whose modules are public (one per command) and hence not protected
    assert not [p for p in (PACKAGE / "cli").glob("_*.py") if p.name != "__init__.py"]


def test_no_module_imports_another_stages_private_module():
    bad = []
    for name, path in _modules().items():
        for imported, line in _imports(name, path):
            parts = imported.split(".")
            private = [k for k, part in enumerate(parts) if k >= 2 and part.startswith("_")
                       and not part.startswith("__")]
            if private and _stage(imported) != _stage(name):
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {imported}")
    assert not bad, "use the stage's public __init__ instead:\n" + "\n".join(bad)


def test_the_ast_scan_sees_a_private_import(tmp_path):
    """The scan above resolves relative imports: ``from ..depth._preview import x`` in outputs/ is one."""
    module = tmp_path / "m.py"
    module.write_text("from ..depth._preview import write_preview\nfrom . import _names\n")
    found = dict(_imports("lfproc.outputs._m", module))
    assert "lfproc.depth._preview.write_preview" in found and "lfproc.outputs._names" in found


def _table() -> dict[str, set[str] | None]:
    """docs/architecture.md's folder table: first column's names -> the lfproc names of "may import" (None for
    "everything")."""
    rows = {}
    for line in DOC.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or not cells[0].startswith("`"):
            continue
        owners = [n.strip("/").removesuffix(".py") for n in re.findall(r"`([^`]+)`", cells[0])]
        may = cells[2]
        names = None if may.startswith("everything") else {
            n.split(".")[0] for n in re.findall(r"`([^`]+)`", may)}
        for owner in owners:
            rows[owner] = names
    return rows


def test_the_may_import_table_is_what_each_folder_imports():
    """Each row's "may import" names (in backticks) are exactly the lfproc folders and modules it imports
    (anywhere: at the top or inside functions); ``lfproc`` stands for the package itself (``__version__``)."""
    table = _table()
    known = {_stage(name) for name in _modules()} - {"lfproc"}
    actual: dict[str, set[str]] = {}
    for name, path in _modules().items():
        stage = _stage(name)
        for imported, _ in _imports(name, path):
            other = _stage(imported)
            other = other if other in known else "lfproc"      # from lfproc import __version__
            if other != stage:
                actual.setdefault(stage, set()).add(other)
    stages = {_stage(name) for name in _modules()} - {"lfproc", "__main__"}
    missing = sorted(stages - set(table))
    assert not missing, f"docs/architecture.md's table has no row for {missing}"
    wrong = []
    for stage in sorted(stages):
        if table[stage] is None:
            continue
        listed, real = table[stage], actual.get(stage, set())
        if listed != real:
            wrong.append(f"{stage}: the table says {sorted(listed)}, the code imports {sorted(real)}")
    assert not wrong, "docs/architecture.md's 'may import' column is stale:\n" + "\n".join(wrong)


# calls that read or write a file themselves (the builtins, numpy, pathlib, the libraries' readers and writers,
# lfproc's atomic writers and TOML reader)
_FILE_CALLS = {"open", "load", "save", "savez", "savez_compressed", "fromfile", "tofile", "memmap", "read_text",
               "write_text", "read_bytes", "write_bytes", "imread", "imwrite", "ZipFile", "TiffFile", "TiffWriter",
               "mmap", "atomic_path", "write_text_atomic", "write_json_atomic", "read_toml"}


def _file_touching_stages() -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for name, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                func = node.func
                called = func.id if isinstance(func, ast.Name) else getattr(func, "attr", None)
                if called in _FILE_CALLS:
                    found.setdefault(_stage(name), []).append(f"{path.relative_to(ROOT)}:{node.lineno} {called}")
    return found


def test_only_the_named_folders_read_and_write_files():
    """The page's sentence "Files are read and written only in ..." names exactly the folders and modules that
    open, load or save files themselves."""
    text = DOC.read_text(encoding="utf-8")
    match = re.search(r"Files are read and written only in (.+?)\.\s*$", text, re.M | re.S)
    assert match, "docs/architecture.md lost its sentence on which folders touch files"
    named = {n.strip("/").removesuffix(".py") for n in re.findall(r"`([^`]+)`", match.group(1).split("\n\n")[0])}
    found = _file_touching_stages()
    outside = {stage: calls for stage, calls in found.items() if stage not in named}
    assert not outside, f"files are touched outside the folders docs/architecture.md names: {outside}"
    assert named == set(found), f"the page names folders that touch no file: {sorted(named - set(found))}"


def test_modules_stay_under_400_lines():
    long = sorted(str(path.relative_to(ROOT)) for path in _modules().values()
                  if len(path.read_text(encoding="utf-8").splitlines()) > MAX_LINES)
    assert set(long) <= LONG_MODULES_BEING_REWRITTEN, f"split these modules (one concern each): {long}"


# ---------------------------------------------------------------------------------------------- one optics model
#: where the kind of main optics may be asked by name: the optics themselves, a microscope's own geometry
#: (view angles, aplanatic shifts, z ranges) and the microscope renderer
OPTICS_MODULES = {"lfproc/camera", "lfproc/geometry/_microscope.py", "lfproc/simulate/_microscope.py"}


def _kind_branches(tree: ast.AST) -> list[tuple[int, str]]:
    """Lines that ask a camera or a result which kind of optics it has, rather than what the optics give."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in ("microscope", "is_microscope"):
            found.append((node.lineno, f".{node.attr}"))
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("getattr", "hasattr")
              and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) and node.args[1].value == "microscope"):
            found.append((node.lineno, f'{node.func.id}(..., "microscope")'))
    return found


def test_nothing_outside_the_optics_branches_on_the_kind_of_optics():
    """Issue 31: the main optics are one parameter behind one interface (``Camera.main_optics``,
    :mod:`lfproc.camera._main_optics`). Code elsewhere names, orders and labels positions by the camera's
    ``object_space`` (unit and origin), places views by ``views_are_orthographic`` and reads apertures through
    ``image_aperture_sine``; it never asks ``camera.main_optics`` / ``is_microscope`` / ``result.microscope``."""
    bad = []
    for path in _modules().values():
        rel = str(path.relative_to(ROOT))
        if any(rel == owner or rel.startswith(owner + "/") for owner in OPTICS_MODULES):
            continue
        for line, what in _kind_branches(ast.parse(path.read_text(encoding="utf-8"))):
            bad.append(f"{rel}:{line} {what}")
    assert not bad, "branch on the main optics' interface instead (docs/architecture.md):\n" + "\n".join(bad)


def test_the_kind_scan_sees_each_idiom():
    tree = ast.parse('a = camera.main_optics\nb = camera.is_microscope\nc = getattr(camera, "microscope", None)\n'
                     'd = geo.space.from_sensor\n')
    assert [what for _, what in _kind_branches(tree)] == [".microscope", ".is_microscope", 'getattr(..., "microscope")']
