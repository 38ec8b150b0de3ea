"""The commands' words for the library's (lfproc/cli/words.py): the library marks the Python arguments its
messages name (```white=```, ```aperture=2.8```) and its how-tos; a Python caller reads them plain, a command
reports each argument as its option of that name (argparse ``dest``) and each how-to as the command to run."""

import ast
import functools
import re
from pathlib import Path

import pytest

from lfproc.cli import build_parser, main
from lfproc.cli import COMMANDS
from lfproc.cli.words import HOW_TO, command_words
from lfproc.errors import ARGUMENT, MARK, python_words
from conftest import SAMPLES

LIBRARY = Path(__file__).resolve().parents[1] / "lfproc"

#: ``name=`` words in library messages that are not marked: values and Python-only arguments (never reworded)
NOT_ARGUMENTS = {
    "a": "the slice parameter's value (at a=0.5), printed as it is by the commands too",
    "upsample": "a value (upsample=8 with 3 slices ...), printed as it is by the commands too",
    "stem": "FocalStack.save / ViewStack.save: Python only",
    "view_mask": "LightField.from_views(views, camera, view_mask=...): Python only",
    "main_optics": "the Camera constructor: Python only",
    "microscope": "the Camera constructor: Python only",
    "backend": "lfproc.deconvolve(backend=...): Python only",
    "operators": "lfproc.deconvolve(operators=...): Python only (the command keeps them in the cache)",
    "oversample": "lfproc.deconvolve / lfproc.wave.build_operators(oversample=...): Python only",
}


def _text(node, src):
    """A message's text with its placeholders as ``{}`` (None for text built otherwise)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        left, right = _text(node.left, src), _text(node.right, src)
        return None if left is None or right is None else left + right
    return None


@functools.lru_cache(maxsize=1)
def library_messages() -> list[tuple[str, str]]:
    """(file, text) of every error and warning the library (all but cli/) raises, and of the strings assigned
    or returned that go into them."""
    found = []
    for path in sorted(LIBRARY.rglob("*.py")):
        if "cli" in path.relative_to(LIBRARY).parts:
            continue
        src = path.read_text()
        for node in ast.walk(ast.parse(src)):
            text = None
            if isinstance(node, ast.Call) and node.args:
                func = node.func   # the called name's last part (get_source_segment re-splits the file: slow)
                name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
                if name.endswith(("LfprocError", "warn")):
                    text = _text(node.args[0], src)
            elif isinstance(node, (ast.Assign, ast.Return)) and isinstance(node.value, (ast.Constant, ast.JoinedStr)):
                text = _text(node.value, src)
            if text:
                found.append((str(path.relative_to(LIBRARY)), text))
    return found



def _options() -> dict:
    """dest -> (command, its first action of that dest), over every command."""
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    found = {}
    for name, sub in commands.items():
        first = {}
        for action in sub._actions:
            first.setdefault(action.dest, action)
        for dest, action in first.items():
            found.setdefault(dest, []).append((name, action))
    return found


def _marks(text: str) -> list:
    return MARK.findall(text)


def _marked_arguments() -> dict:
    """argument name -> the (file, message) pairs that mark it."""
    found = {}
    for path, text in library_messages():
        for mark in _marks(text):
            argument = ARGUMENT.fullmatch(mark)
            if argument:
                found.setdefault(argument.group(1), []).append((path, text))
    return found


#: arguments the library marks that no command has (a Python call's alternatives the commands never offer)
PYTHON_ONLY = {"z_um": "lfproc.focal_stack(z_um=...): refocus takes --z-range (z_range_um); deconvolve's --z-range "
                       "is z_um"}


def test_every_argument_the_library_marks_is_an_option_of_a_command():
    marked = _marked_arguments()
    assert {"white", "white_dir", "grid", "dark", "camera", "aperture", "z_range_um", "white_is_white"} <= set(marked)
    options = _options()
    missing = {name: where for name, where in marked.items() if name not in options}
    assert not missing, f"no command has an option of these names (argparse dest): {sorted(missing)}"
    for name, owners in options.items():
        for command, action in owners:
            assert action.option_strings or action.metavar, (command, name)   # a flag, or a positional's name


#: the arguments of lfproc.prepare_decoding / read_light_field, which every decoding command reports
DECODE_ARGUMENTS = {"camera", "grid", "white", "white_dir", "dark", "white_is_white", "decode_interpolation",
                    "demosaic", "capture"}


def test_every_decoding_command_has_an_option_for_each_decode_argument():
    """The decode setup's messages (white=, grid=, dark=, ...) reach every command that decodes: each has an
    option of each name (batch and the viewer name their inputs otherwise: INPUT, folders or pictures too)."""
    decoding = {command for command, _ in _options()["white_dir"]}
    assert decoding == {"decode", "refocus", "views", "depth", "deconvolve", "viewer", "batch"}
    for command in decoding:
        dests = {dest for dest, owners in _options().items() if any(name == command for name, _ in owners)}
        missing = DECODE_ARGUMENTS - dests
        assert missing <= ({"capture"} if command == "batch" else set()), (command, missing)


def test_the_commands_that_report_an_argument_name_it_by_their_flag():
    """Each command that has an option of the marked name reports the mark as that option (never Python words),
    whichever command it is."""
    options = _options()
    for name, owners in options.items():
        for command, action in owners:
            said = command_words(f"pass `{name}=`; e.g. `{name}=...`", command)
            assert f"{name}=" not in said and "`" not in said, (command, name, said)
            assert said.startswith(f"pass {action.option_strings[0] if action.option_strings else action.metavar}")


def test_no_library_message_names_an_argument_unmarked():
    """Every argument a command has is marked where a library message names it (a command could not word it)."""
    names = set(_options()) | set(_marked_arguments())
    unmarked = re.compile(r"(?<![\w./=`-])(" + "|".join(sorted(names - set(NOT_ARGUMENTS), key=len, reverse=True))
                          + r")=")
    found = [(path, text) for path, text in library_messages() if unmarked.search(MARK.sub("", text))]
    assert not found


def test_no_library_message_names_a_flag_or_a_command():
    """Flags and commands belong to the commands (:data:`HOW_TO`, the options' names); the library's messages
    speak Python: ``lfproc.calibrate_white(...)``, never ``lfproc calibrate`` or ``--white``."""
    command = re.compile(r"(?<![\w.])lfproc (" + "|".join(COMMANDS) + r")\b|(?<![\w-])--[a-z]")
    flagged = [(path, text) for path, text in library_messages() if command.search(text)]
    # data, not messages: notes a camera file or a picture's sidecar carries (written for the commands' users)
    flagged = [(p, t) for p, t in flagged if p not in ("io/_lytro_camera.py", "outputs/_lytro_pictures.py")
               or t.startswith("{}:")]
    assert not flagged


def test_every_how_to_the_library_marks_has_the_commands_words():
    how_tos = {mark for _, text in library_messages() for mark in _marks(text) if not ARGUMENT.fullmatch(mark)}
    assert how_tos == set(HOW_TO)
    names_a_command = re.compile(r"\blfproc (" + "|".join(COMMANDS) + r")\b")
    for python, command in HOW_TO.items():
        assert "lfproc." in python and names_a_command.search(command), (python, command)


@pytest.mark.parametrize("command, library, said", [
    # the four forms, as the messages of lfproc.prepare_decoding and the checks below it are written
    ("refocus", "give `white=...` or `white_dir=...`, not both", "give --white WHITE or --white-dir DIR, not both"),
    ("decode", "decoding a capture needs `white=...` (a white image), `grid=...` (`a LensGrid from "
     "lfproc.calibrate_white, or its saved file`) or `white_dir=...` (a Lytro calibration folder)",
     "decoding a capture needs --white WHITE (a white image), --calib GRID.json (from lfproc calibrate) or "
     "--white-dir DIR (a Lytro calibration folder)"),
    ("decode", "d2.png: this dark frame differs from the one g.json was calibrated with (d1.png); pass that one, or "
     "fit the grid again with `dark=d2.png`", "d2.png: this dark frame differs from the one g.json was calibrated "
     "with (d1.png); pass that one, or fit the grid again with --dark d2.png"),
    ("views", "`white_dir=/cal`: picks a white image", "--white-dir /cal: picks a white image"),
    ("depth", "pass the white image of this camera as `white=`", "pass the white image of this camera as --white"),
    ("geometry", "`aperture=0.5` is wider than the main lens (f/4); give f/4", "--aperture 0.5 is wider than the "
     "main lens (f/4); give f/4"),
    ("refocus", "`aperture='f8'` is not an f-number; give one from f/4 to f/275, e.g. `aperture=8`",
     "--aperture 'f8' is not an f-number; give one from f/4 to f/275, e.g. --aperture 8"),
    ("views", "no view that carries light lies inside f/8; give a wider `aperture=`", "no view that carries light "
     "lies inside f/8; give a wider aperture="),                       # views has no --aperture: Python words
    ("depth", "`z_range_um=` must be two different finite depths in um", "--z-range must be two different finite "
     "depths in um"),
    ("deconvolve", "`z_um=` asks for the same plane twice", "--z-range asks for the same plane twice"),
    ("geometry", "camera file not found; pass an existing TOML file to `camera=`", "camera file not found; pass an "
     "existing TOML file to --camera"),
    ("geometry", "the view gap G must be a non-zero number of views (e.g. `gap=1`)", "the view gap G must be a "
     "non-zero number of views (e.g. --gap 1)"),
    ("batch", "out: cannot write in the output folder (Permission denied); check `outdir=...`", "out: cannot write "
     "in the output folder (Permission denied); check -o OUTDIR"),
    ("decode", "pass the capture as `capture=` and the white image as `white=`", "pass the capture as RAW and the "
     "white image as --white"),
    ("batch", "`scheduler=tcp://x:8786`: cannot reach", "--scheduler tcp://x:8786: cannot reach"),
    # a positional argument by its metavar, the same mark an option elsewhere
    ("calibrate", "give a white image as `white=`, or pass `white_is_white=True` if this is one", "give a white "
     "image as WHITE, or pass --white-is-white if this is one"),
    ("calibrate", "pass the white image as `white=` and the dark frame (lens cap on) as `dark=`", "pass the white "
     "image as WHITE and the dark frame (lens cap on) as --dark"),
    ("decode", "pass the white image as `white=` and the dark frame (lens cap on) as `dark=`", "pass the white "
     "image as --white and the dark frame (lens cap on) as --dark"),
    # how-tos
    ("decode", "g.json: grid file not found; check the path, or make one with "
     "`lfproc.calibrate_white(white, camera).save(path)`", "g.json: grid file not found; check the path, or make "
     "one with lfproc calibrate WHITE --camera CAM -o GRID.json"),
    ("export", "x.lfp: describes a microscope, not a Lytro camera; pass a camera file with a [main_lens] (e.g. from "
     "`lfproc.read_camera(path) of a Lytro file of the same camera`)", "x.lfp: describes a microscope, not a Lytro "
     "camera; pass a camera file with a [main_lens] (e.g. from 'lfproc camera' on a Lytro file of the same camera)"),
    # left as they are: unmarked words, values, paths
    ("refocus", "c.png: in 2 slice(s) (up to a=+1.5) fewer than half", "c.png: in 2 slice(s) (up to a=+1.5) fewer "
     "than half"),
    ("refocus", "refocus: upsample=8 with 3 slice(s) would produce", "refocus: upsample=8 with 3 slice(s) would "
     "produce"),
    ("decode", "/data/white=1/dark=2.png: no such file", "/data/white=1/dark=2.png: no such file"),
])
def test_marked_words_become_the_commands_words(command, library, said):
    assert command_words(library, command) == said
    assert command_words(said, command) == said          # the commands' own messages pass unchanged
    assert "`" not in python_words(library) and "--" not in python_words(library)


def test_a_command_reports_the_library_error_with_its_flags(capsys, tmp_path):
    camera = SAMPLES / "cameras" / "paper-f100.toml"
    assert main(["geometry", "--camera", str(camera), "--aperture", "0.5"]) == 2
    assert capsys.readouterr().err == ("lfproc geometry: error: --aperture 0.5 is wider than the main lens (f/4); "
                                       "give f/4 or narrower (up to f/275, one view)\n")
    assert main(["geometry", "--camera", str(tmp_path / "none.toml")]) == 2
    assert capsys.readouterr().err == (f"lfproc geometry: error: {tmp_path / 'none.toml'}: camera file not found; "
                                       f"pass an existing TOML file to --camera\n")
