"""``lfproc info``: what a file is and holds (Lytro containers and raws, camera raws, images)."""

from __future__ import annotations

import math
import sys


def register(sub) -> None:
    p = sub.add_parser("info", help="what a capture or image file is and holds",
                       description="Describe a file without decoding it: format, whether it holds a raw light "
                                   "field, size, bit depth, CFA, levels; for Lytro files the camera model and "
                                   "serial, lens data and every section of the container with its SHA-1 check.")
    p.add_argument("file", metavar="FILE", nargs="?",
                   help="a capture, white image or picture: Lytro .lfr/.lfp or .raw with its metadata, camera raw, "
                        "TIFF, PNG, EXR, …, or an image lfproc wrote (its embedded tags are shown)")
    p.add_argument("--samples", action="store_true",
                   help="print where the bundled samples are (inside the installed package) and what each is")
    p.add_argument("--cache", action="store_true",
                   help="print where the decoder cache is (LFPROC_CACHE_DIR), how many entries it holds and their "
                        "size (LFPROC_CACHE_MAX_GB bounds it; LFPROC_NO_CACHE=1 disables it)")
    p.add_argument("--clear-cache", action="store_true", help="remove every entry of the decoder cache")
    p.add_argument("--json", action="store_true", help="print one JSON object (strict JSON: infinity is null)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..io import describe_file
    from .common import dumps_strict
    from .words import command_words

    if args.samples:
        return _print_samples(args.json)
    if args.cache or args.clear_cache:
        return _print_cache(args.clear_cache, args.json)
    if args.file is None:
        from ..errors import LfprocError
        raise LfprocError("lfproc info needs a FILE (or --samples to list the bundled samples, --cache to show the "
                          "decoder cache)")
    # a description's notes mark what Python calls would do: said here as the commands do it
    info = {key: command_words(value, "info") if isinstance(value, str) else value
            for key, value in describe_file(args.file).items()}
    if args.json:
        sys.stdout.write(dumps_strict(info, indent=1) + "\n")
        return 0
    sys.stdout.write(format_info(info))
    return 0


def _print_samples(as_json: bool) -> int:
    from ..sample_data import SAMPLES, SAMPLES_DIR
    from .common import dumps_strict

    paths = {name: str(SAMPLES_DIR / name) for name in SAMPLES}
    if as_json:
        sys.stdout.write(dumps_strict({"samples_dir": str(SAMPLES_DIR), "samples": paths}, indent=1) + "\n")
        return 0
    lines = [f"bundled samples in {SAMPLES_DIR}:"]
    lines += [f"  {paths[name]}\n      {what}" for name, what in SAMPLES.items()]
    lines.append(f"try: lfproc refocus {paths['sample/capture.png']} --camera {paths['sample/camera.toml']} "
                 f"--white {paths['sample/white.png']} --a 0:2:0.5 -o refocused/")
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


def format_info(info: dict) -> str:
    """The description as aligned ``key: value`` lines, sections as a table."""
    lines = []
    for key, value in info.items():
        if key in ("sections", "path"):
            continue
        if key == "tags" and isinstance(value, dict):
            lines.append("tags (embedded by lfproc):")
            for k, v in value.items():
                if _is_records(v):      # a z-stack's slices: one line each (their shared provenance once, after)
                    lines.append(f"  {k} ({len(v)}):")
                    lines += ["    " + ", ".join(f"{name} {_fmt(x)}" for name, x in row.items() if name != "provenance")
                              for row in v]
                    if isinstance(v[0].get("provenance"), dict):
                        lines.append(f"  {'provenance':20s} {_fmt(v[0]['provenance'])}")
                elif isinstance(v, dict):   # a nested record (an exported Lytro picture's camera): its own lines
                    lines.append(f"  {k}:")
                    lines += [f"    {name:18s} {_fmt(x)}" for name, x in v.items()]
                else:
                    lines.append(f"  {k:20s} {_fmt(v)}")
            continue
        rows = []
        if isinstance(value, dict):
            rows = [item for v in value.values() if isinstance(v, list) for item in v if isinstance(item, dict)]
            value = ", ".join(f"{k} {_fmt(v)}" for k, v in value.items() if v is not None and not
                              (isinstance(v, list) and v and isinstance(v[0], dict)))
        lines.append(f"{key:22s} {_fmt(value)}")
        lines += ["  " + ", ".join(f"{k} {_fmt(v)}" for k, v in row.items() if v is not None) for row in rows]
    sections = info.get("sections") or []
    if sections:
        lines.append(f"sections ({len(sections)}):")
        for s in sections:
            lines.append(f"  {s['kind']} {s['length']:>10d} B  {s['sha1'][:17]}…  "
                         f"{'ok' if s['sha1_ok'] else 'SHA-1 MISMATCH'}  {s['content']}")
    return f"{info.get('path', '')}\n" + "\n".join(lines) + "\n"


def _is_records(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(item, dict) for item in value)


def _fmt(value) -> str:
    if isinstance(value, dict):   # a file by its hash (provenance), or a nested record on one line
        if set(value) == {"path", "sha256"}:
            return f"{value['path']} (sha256 {str(value['sha256'])[:12]}…)"
        return ", ".join(f"{k} {_fmt(v)}" for k, v in value.items())
    if isinstance(value, float):
        return "inf" if math.isinf(value) else f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    if isinstance(value, dict):   # a record nested deeper (a sidecar's provenance): key value pairs
        return "(" + ", ".join(f"{k} {_fmt(v)}" for k, v in value.items()) + ")"
    return str(value)


def _print_cache(clear: bool, as_json: bool) -> int:
    """``lfproc info --cache`` / ``--clear-cache``: the decoder cache's folder, entries and size; or empty it."""
    from .. import decoder_cache
    from .common import dumps_strict

    found = decoder_cache.summary()
    if found is not None and clear:
        found["removed"] = decoder_cache.clear(found["folder"])
    if as_json:
        sys.stdout.write(dumps_strict({"enabled": found is not None, **(found or {})}, indent=1) + "\n")
    elif found is None:
        print("decoder cache disabled (LFPROC_NO_CACHE)")
    elif clear:
        print(f"{found['folder']}: removed {found['removed']} entries")
    else:
        print(f"{found['folder']}: {found['entries']} entries, {found['bytes'] / 1e9:.2f} GB of at most "
              f"{found['max_bytes'] / 1e9:.2f} GB (LFPROC_CACHE_MAX_GB)")
    return 0
