"""The commands' words for the library's (lfproc/cli/words.py): the library names Python arguments in its
messages (``white=``, ``aperture=2.8``), the commands report them with their flags, exactly as they did
when the library wrote the flags itself."""

import ast
import functools
import re
from pathlib import Path

import pytest

from lfproc.cli import build_parser, main
from lfproc.cli.words import FLAGS, PHRASES, command_words
from conftest import SAMPLES

LIBRARY = Path(__file__).resolve().parents[1] / "lfproc"

#: ``name=`` words in library messages that are not an argument a command has (never reworded)
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
    """(file, text) of every error and warning the library (all but cli/) raises, and of the module-level
    strings that go into them."""
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
            elif isinstance(node, ast.Assign) and isinstance(node.value, (ast.Constant, ast.JoinedStr)):
                text = _text(node.value, src)
            if text:
                found.append((str(path.relative_to(LIBRARY)), text))
    return found


_NAMED = re.compile(r"(?<![\w./=-])([a-z_][a-z0-9_]*)=")


def test_every_argument_the_library_names_has_its_flag():
    named = {word for _, text in library_messages() for word in _NAMED.findall(text)}
    assert {"white", "white_dir", "grid", "dark", "camera", "aperture", "z_range_um", "white_is_white"} <= named
    unknown = named - set(FLAGS) - set(NOT_ARGUMENTS)
    assert not unknown, f"library messages name {sorted(unknown)}: give each its flag in lfproc/cli/words.py"


def test_no_library_message_names_a_flag():
    """Flags belong to the commands; a command named whole ('lfproc calibrate WHITE --camera CAM', lfproc info
    --samples) may show them."""
    commands = re.compile(r"'[^']*'|\blfproc [a-z]+ --[a-z-]+")
    flagged = [(path, text) for path, text in library_messages()
               if re.search(r"(?<![\w-])--[a-z]", commands.sub("", text))]
    # data, not messages: notes a camera file or a picture's sidecar carries (written by the commands)
    flagged = [(p, t) for p, t in flagged if p not in ("io/_lytro_camera.py", "outputs/_lytro_pictures.py")
               or t.startswith("{}:")]
    assert not flagged


def test_every_flag_is_an_option_of_a_command():
    options, positionals = set(), set()
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    for sub in commands.values():
        for action in sub._actions:
            options.update(action.option_strings)
            if not action.option_strings:
                positionals.add(action.metavar)
    for word, (flag, metavar) in FLAGS.items():
        if flag is None:
            assert metavar in positionals, word
        else:
            assert flag in options, (word, flag)


@pytest.mark.parametrize("library, command", [
    # the four forms, as the messages of lfproc.prepare_decoding and the checks below it are written
    ("give white=... or white_dir=..., not both", "give --white WHITE or --white-dir DIR, not both"),
    ("give white=... (a white image), white_dir=... (a Lytro calibration folder) or grid=... (from lfproc "
     "calibrate)", "give --white WHITE (a white image), --white-dir DIR (a Lytro calibration folder) or --calib "
     "GRID.json (from lfproc calibrate)"),
    ("d2.png: this dark frame differs from the one g.json was calibrated with (d1.png); pass that one, or "
     "calibrate again with dark=d2.png", "d2.png: this dark frame differs from the one g.json was calibrated with "
     "(d1.png); pass that one, or calibrate again with --dark d2.png"),
    ("white_dir=/cal: picks a white image", "--white-dir /cal: picks a white image"),
    ("pass the white image of this camera as white=", "pass the white image of this camera as --white"),
    ("aperture=0.5 is wider than the main lens (f/4); give f/4", "--aperture 0.5 is wider than the main lens (f/4); "
     "give f/4"),
    ("aperture='f8' is not an f-number; give one from f/4 to f/275, e.g. aperture=8",
     "--aperture 'f8' is not an f-number; give one from f/4 to f/275, e.g. --aperture 8"),
    ("no view that carries light lies inside f/8; give a wider aperture=", "no view that carries light lies inside "
     "f/8; give a wider --aperture"),
    ("z_range_um=-50.0:inf must be finite micrometres, e.g. -50:50", "--z-range -50.0:inf must be finite "
     "micrometres, e.g. -50:50"),
    ("z_range_um= step must be a positive number", "--z-range step must be a positive number"),
    ("give a z range (z_range_um=...) instead", "give a z range (--z-range Z0:Z1) instead"),
    ("camera file not found; pass an existing TOML file to camera=", "camera file not found; pass an existing TOML "
     "file to --camera"),
    ("the view gap G must be a non-zero number of views (e.g. gap=1)", "the view gap G must be a non-zero number "
     "of views (e.g. --gap 1)"),
    ("out: cannot write in the output folder (Permission denied); check outdir=...", "out: cannot write in the "
     "output folder (Permission denied); check -o OUTDIR"),
    ("pass the capture as capture= and the white image as white=", "pass the capture as RAW and the white image "
     "as --white"),
    ("scheduler=tcp://x:8786: cannot reach", "--scheduler tcp://x:8786: cannot reach"),
    # the phrases
    ("give a white image (a uniform bright surface, e.g. through a diffuser) as white=, or pass white_is_white=True "
     "if this is one", "give a white image (a uniform bright surface, e.g. through a diffuser) as WHITE, or pass "
     "--white-is-white if this is one"),
    ("pass the white image as white= and the dark frame (lens cap on) as dark=", "pass the white image as WHITE "
     "(--white) and the dark frame (lens cap on) as --dark"),
    ("if it is a white image, say so with white_is_white=True", "if it is a white image, say so with "
     "--white-is-white (white_is_white=True)"),
    # left as they are: values, quoted commands, paths
    ("c.png: in 2 slice(s) (up to a=+1.5) fewer than half", "c.png: in 2 slice(s) (up to a=+1.5) fewer than half"),
    ("refocus: upsample=8 with 3 slice(s) would produce", "refocus: upsample=8 with 3 slice(s) would produce"),
    ("g.json: grid file not found; run 'lfproc calibrate WHITE --camera CAM -o g.json'",
     "g.json: grid file not found; run 'lfproc calibrate WHITE --camera CAM -o g.json'"),
    ("/data/white=1/dark=2.png: no such file", "/data/white=1/dark=2.png: no such file"),
])
def test_library_words_become_the_commands_words(library, command):
    assert command_words(library) == command
    if "(white_is_white=True)" not in command:   # (the warning that gives both spellings is not reworded twice)
        assert command_words(command) == command     # the commands' own messages pass unchanged


def test_every_library_message_reads_in_flags_in_a_command():
    """No argument a command has is left in Python words in what a command reports (the one deliberate
    exception: the warning that gives both spellings)."""
    arguments = re.compile(r"(?<![\w./=-])(" + "|".join(FLAGS) + r")=")
    for path, text in library_messages():
        reworded = command_words(text)
        for both in PHRASES.values():
            reworded = reworded.replace(both, "")
        assert not arguments.search(reworded), (path, text, reworded)


def test_a_command_reports_the_library_error_with_its_flags(capsys, tmp_path):
    camera = SAMPLES / "cameras" / "paper-f100.toml"
    assert main(["geometry", "--camera", str(camera), "--aperture", "0.5"]) == 2
    assert capsys.readouterr().err == ("lfproc geometry: error: --aperture 0.5 is wider than the main lens (f/4); "
                                       "give f/4 or narrower (up to f/275, one view)\n")
    assert main(["geometry", "--camera", str(tmp_path / "none.toml")]) == 2
    assert capsys.readouterr().err == (f"lfproc geometry: error: {tmp_path / 'none.toml'}: camera file not found; "
                                       f"pass an existing TOML file to --camera\n")
