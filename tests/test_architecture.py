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
    import importlinter  # noqa: F401  (the test extra installs it: the layering check must not be skipped)
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
#: where the kind of main optics may be asked by name (docs/architecture.md, "One optics model"): the optics
#: themselves, and each kind's own geometry, renderer and files
OPTICS_MODULES = {
    "lfproc/camera": "the optics: MainLens, Microscope, their camera-file tables and transfers",
    "lfproc/geometry/_main_lens.py": "a main lens's own geometry: its lens, the plane of its virtual cameras",
    "lfproc/geometry/_diffraction.py": "a main lens's own: the Airy check of its working f-number (Eq. 22)",
    "lfproc/geometry/_triangulation.py": "a main lens's own: PlenoptiSign's triangulation between virtual cameras",
    "lfproc/geometry/_real_rays.py": "a main lens's own: real rays through its surfaces",
    "lfproc/geometry/_ray_model.py": "a main lens's own: PlenoptiSign's parameter set",
    "lfproc/geometry/_microscope.py": "a microscope's own geometry: z per a, aplanatic per-view shifts",
    "lfproc/simulate": "the renderers: a thin main lens's ray tracer and the microscope's",
    "lfproc/io/_lytro_camera.py": "a Lytro camera's main lens from its metadata",
    "lfproc/io/_lytro_lambda.py": "Lytro's lambda: the focus unit of its main lens",
}

#: attributes that stand for the kind of optics (the old flags, and asking a camera which kind it has)
KIND_FLAGS = {"from_sensor", "views_are_orthographic", "views_have_angles", "is_microscope", "require_main_lens",
              "microscope", "main_lens", "main_focal_length_mm", "main_principal_plane_gap_mm",
              "main_lens_prescription", "sensor_to_main_lens_mm", "signed_depths"}
#: attributes of the object space whose comparison with a literal stands for the kind (``space.unit == "um"``)
SPACE_NAMES = {"unit", "symbol", "letter", "origin", "position_key", "keys", "per_mm"}
#: geometry functions of one kind only (a microscope's; a main lens's lens), and the ones they replaced
KIND_FUNCTIONS = {"z_per_a_um", "na_views", "aplanatic_gain", "paraxial_depth_error", "uses_aplanatic",
                  "microscope_slices", "main_lens_of", "microscope_views", "plan_z_range", "views_inside_na",
                  "pupil_positions_mm", "refocus_parameter_z", "z_step_advice"}


def _kind_only_attributes() -> set:
    """Public members of MainLens and Microscope that are not members of the MainOptics interface."""
    import dataclasses

    from lfproc.camera import MainLens, MainOptics, Microscope
    interface = {n for n in dir(MainOptics) if not n.startswith("_")} | {"wave_optics"}
    members = {n for cls in (MainLens, Microscope) for n in [*dir(cls), *(f.name for f in dataclasses.fields(cls))]}
    return {n for n in members if not n.startswith("_")} - interface


def _optics_names(tree: ast.AST) -> set:
    """Names bound to a camera's main optics anywhere in the module (``optics = camera.main_optics``)."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Attribute) and node.value.attr == "main_optics":
            names |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return names


def _is_optics(node: ast.AST, names: set) -> bool:
    return (isinstance(node, ast.Attribute) and node.attr == "main_optics") or \
        (isinstance(node, ast.Name) and node.id in names)


def _kind_questions(tree: ast.AST, kind_only: set) -> list[tuple[int, str]]:
    """Lines that ask which kind the main optics are, rather than asking the optics to do something: kind flags,
    the object space's unit or keys compared with a literal, isinstance against MainLens or Microscope, reads of
    members only one kind has (on ``camera.main_optics`` or a name bound to it), calls of one kind's geometry."""
    names = _optics_names(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in KIND_FLAGS:
            found.append((node.lineno, f".{node.attr}"))
        elif isinstance(node, ast.Attribute) and node.attr in kind_only and _is_optics(node.value, names):
            found.append((node.lineno, f"main_optics.{node.attr}"))
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            literal = any(isinstance(x, ast.Constant) and isinstance(x.value, str) or isinstance(x, (ast.Tuple, ast.Set))
                          and any(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in x.elts)
                          for x in sides)
            named = [x.attr for x in sides if isinstance(x, ast.Attribute) and x.attr in SPACE_NAMES]
            if literal and named:
                found.append((node.lineno, f".{named[0]} compared with a literal"))
        elif isinstance(node, ast.Call):
            func = node.func
            name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""
            if name == "isinstance" and len(node.args) == 2 and {"MainLens", "Microscope"} & {
                    n.id if isinstance(n, ast.Name) else getattr(n, "attr", "") for n in ast.walk(node.args[1])}:
                found.append((node.lineno, "isinstance(..., MainLens|Microscope)"))
            elif name in ("getattr", "hasattr") and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) \
                    and (node.args[1].value in KIND_FLAGS
                         or node.args[1].value in kind_only and _is_optics(node.args[0], names)):
                found.append((node.lineno, f'{name}(..., "{node.args[1].value}")'))
            elif name in KIND_FUNCTIONS:
                found.append((node.lineno, f"{name}()"))
    return found


def _owned_by_optics(rel: str) -> bool:
    return any(rel == owner or rel.startswith(owner + "/") for owner in OPTICS_MODULES)


def test_nothing_outside_the_optics_asks_which_kind_of_optics_it_has():
    """Issues 31 and 37: the main optics are one parameter behind one interface (``Camera.main_optics``,
    :class:`lfproc.camera.MainOptics`). Code outside the optics and each kind's own modules asks them to *do*
    things (place their views, invert a position, give their usable range, their object space's order and
    words); it never reads a flag that stands for the kind, compares the object space's unit or keys with a
    literal, asks ``isinstance(..., MainLens|Microscope)``, reads a member only one kind has, or calls one kind's
    geometry (a microscope's z per a, a main lens's ``main_lens_of``)."""
    kind_only = _kind_only_attributes()
    bad = []
    for path in _modules().values():
        rel = str(path.relative_to(ROOT))
        if _owned_by_optics(rel):
            continue
        for line, what in _kind_questions(ast.parse(path.read_text(encoding="utf-8")), kind_only):
            bad.append(f"{rel}:{line} {what}")
    assert not bad, "ask the main optics to do it instead (docs/architecture.md, One optics model):\n" + "\n".join(bad)


def test_the_kind_scan_sees_each_idiom():
    kind_only = _kind_only_attributes()
    assert {"focal_length_mm", "f_number", "prescription", "objective_magnification", "numerical_aperture",
            "immersion_index", "aplanatic"} <= kind_only
    assert not {"object_space", "place_views", "usable_range", "refocus_parameter", "lateral_sampling_um"} & kind_only
    source = ("a = camera.microscope\nb = geo.space.from_sensor\nc = optics.views_are_orthographic\n"
              "d = getattr(camera, 'microscope', None)\ne = space.unit == 'um'\nf = space.position_key in ('z_um',)\n"
              "g = isinstance(camera.main_optics, MainLens)\nh = camera.main_optics.f_number\n"
              "optics = camera.main_optics\ni = optics.numerical_aperture\nj = geometry.z_per_a_um(camera)\n"
              "k = main_lens_of(camera, 'x')\nl = camera.require_main_lens('x')\n"
              "# asking the optics to do things, and reading what they give, is fine:\n"
              "m = optics.place_views(camera, [0]).orthographic\nn = space.position_key == name\n"
              "o = optics.usable_range(camera).low\np = lens.focal_length_mm\n")
    found = [line for line, _ in _kind_questions(ast.parse(source), kind_only)]
    assert found == [1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12, 13], found


def test_the_optics_own_modules_are_the_ones_the_page_names():
    """docs/architecture.md names every module allowed to know the kind of optics, and each exists."""
    text = DOC.read_text(encoding="utf-8")
    for owner in OPTICS_MODULES:
        assert (ROOT / owner).exists(), owner
        assert f"`{owner.removeprefix('lfproc/')}`" in text, f"docs/architecture.md does not name {owner}"
