"""The contract's Python entry points, and that importing lfproc (or running `lfproc geometry`) stays light."""

import subprocess
import sys

import numpy as np

HEAVY = ("numba", "cv2", "OpenImageIO", "rawpy", "matplotlib", "distributed")


def run_python(code):
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def test_import_loads_no_heavy_library():
    loaded = run_python(f"import sys, lfproc; print([m for m in {HEAVY!r} if m in sys.modules])")
    assert loaded == "[]"


def test_geometry_command_loads_no_heavy_library(paper_camera):
    code = (f"import sys, io, contextlib; from lfproc.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()): main(['geometry', '--camera', {str(paper_camera)!r}])\n"
            f"print([m for m in {HEAVY!r} if m in sys.modules])")
    assert run_python(code) == "[]"


def test_contract_callables_whatever_was_imported_first():
    code = ("import numpy as np, lfproc, lfproc.refocusing, lfproc.viewpoints, lfproc.outputs\n"
            "v = np.arange(3 * 3 * 4 * 5, dtype=np.float32).reshape(3, 3, 4, 5, 1)\n"
            "lf = lfproc.LightField.from_views(v)\n"
            "print(lfproc.refocus(lf, 1).shape, lfproc.refocus(lf, [0, 1.5]).shape, lfproc.viewpoints(lf).shape)")
    assert run_python(code) == "(4, 5, 1) (2, 4, 5, 1) (3, 3, 4, 5, 1)"


def test_viewpoints_are_the_views_and_refocus_at_zero_is_their_mean():
    import lfproc

    views = np.random.default_rng(0).random((5, 5, 6, 7, 3)).astype(np.float32)
    lf = lfproc.LightField.from_views(views)
    assert lfproc.viewpoints(lf) is lf.views
    np.testing.assert_allclose(lfproc.refocus(lf, 0.0), views.mean(axis=(0, 1)), rtol=1e-6)
