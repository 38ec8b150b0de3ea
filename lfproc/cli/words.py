"""The commands' words for the library's marks: a library message marks each argument it names (```white=```,
```aperture=2.8```) and each how-to in Python (```lfproc.calibrate_white(white, camera).save(path)```)
(:mod:`lfproc.errors`); a command reports it with its own words.

An argument becomes the command's option of that name (the argparse option whose ``dest`` is the argument's
name, so a new option needs no edit here), in the form the mark gives:

=====================  ==========================  ===========================================
mark (Python)          command                     e.g.
=====================  ==========================  ===========================================
```name=```            the flag                    ``decode with camera=`` → ``--camera``
```name=...```         the flag and its metavar    ``pass white=...`` → ``--white WHITE``
```name=VALUE```       the flag and the value      ``dark=d.tif`` → ``--dark d.tif``
```name=True```        the flag (a switch)         ``white_is_white=True`` → ``--white-is-white``
=====================  ==========================  ===========================================

A positional argument is named by its metavar (``WHITE`` of ``lfproc calibrate``). An argument the command has
no option for, and a how-to :data:`HOW_TO` does not list, stay in Python words.
"""

from __future__ import annotations

import functools

from ..errors import ARGUMENT, MARK

#: the API's how-tos (marked in library messages) -> what a command's user runs instead
HOW_TO = {
    "lfproc.calibrate_white(white, camera).save(path)": "lfproc calibrate WHITE --camera CAM -o GRID.json",
    "lfproc.read_light_field(...).save(path)": "'lfproc decode'",
    "lfproc.calibrate_white": "lfproc calibrate",
    "a LensGrid from lfproc.calibrate_white, or its saved file": "from lfproc calibrate",
    "lfproc.sample_path() is their folder": "lfproc info --samples",
    "lfproc.read_camera(path) of a Lytro file of the same camera": "'lfproc camera' on a Lytro file of the same "
                                                                   "camera",
    "lfproc.read_camera(path) reads it from a Lytro file's metadata": "'lfproc camera' writes it from a Lytro "
                                                                      "file's metadata",
    "read it with lfproc.read_camera(path), which reads camera files, napari-LF's metadata.txt and Lytro files":
        "write a camera file from it with 'lfproc camera'",
    "lfproc.outputs.export_picture": "'lfproc export'",
    "lfproc.outputs.export_picture(..., camera=...) gives them": "'lfproc export --camera CAM.toml' gives them",
    "lfproc.read_camera": "lfproc camera",
    "lfproc.read_camera(path) reads it as a camera": "lfproc.read_camera reads it as a camera, the command lfproc "
                                                     "camera writes a camera file from it",
    "a lens grid, the file lfproc.calibrate_white(...).save(path) writes: pass it as grid=": "a lens grid, lfproc "
                                                                                         "calibrate's GRID.json: "
                                                                                         "pass it as --calib",
    "read it with lfproc.read_light_field": "use lfproc refocus, views or depth on it",
    "for many make one setup with lfproc.prepare_decoding(camera, white=...) and call its .decode(path) for each "
    "file": "for many, give lfproc batch their folder",
}


def command_words(marked: str, command: str) -> str:
    """``marked`` (a library message with its marks, ``error.marked``) as ``lfproc command`` reports it."""
    options = _options(command)

    def word(match) -> str:
        text = match.group(1)
        argument = ARGUMENT.fullmatch(text)
        if argument is None:
            return HOW_TO.get(text, text)
        name, value = argument.groups()
        return _flag(options[name], value) if name in options else text

    return MARK.sub(word, marked)


def _flag(action, value: str) -> str:
    """How ``lfproc COMMAND`` names its option ``action`` given the value ``value`` (the mark's form)."""
    metavar = action.metavar or action.dest.upper()
    if not action.option_strings:
        return metavar                                # a positional argument: WHITE, RAW
    flag = action.option_strings[0]
    if value in ("", "True"):
        return flag
    return f"{flag} {metavar if value == '...' else value}"


@functools.lru_cache(maxsize=None)
def _options(command: str) -> dict:
    """``lfproc command``'s arguments by ``dest`` (the first option of a ``dest`` when two share it)."""
    from . import build_parser

    parser = build_parser()
    commands = next(action for action in parser._actions if action.dest == "command").choices
    options = {}
    for action in commands[command]._actions:
        options.setdefault(action.dest, action)
    return options
