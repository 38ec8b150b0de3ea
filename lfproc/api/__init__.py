"""The Python API (contract, ARCHITECTURE.md "Python API"): from files or arrays to tagged results.

What a notebook user writes, and what the commands, batch, demo and viewer are built on::

    grid = lfproc.calibrate_white("white.png", cam)                      # -> LensGrid
    grid.save("grid.json")                                               # what `lfproc calibrate -o` writes
    lf = lfproc.read_light_field("capture.png", cam, grid=grid)          # -> LightField
    setup = lfproc.prepare_decoding(cam, white="white.png")              # -> DecodeSetup: many captures,
    lfs = [setup.decode(path) for path in captures]                      #    the decoder derived once
    fs = lfproc.focal_stack(lf, a=[0.5, 1.0])                            # -> FocalStack (images + tags)
    vs = lfproc.view_stack(lf)                                           # -> ViewStack (lit views + tags)
    dm = lfproc.depth_map(lf)                                            # -> DepthMap (arrays + tags)
    vol = lfproc.deconvolve(lf, z_um=[-20, 0, 20], superres=3)           # -> Volume (microscopes)
    ops = lfproc.prepare_deconvolution(lf, z_um=[-20, 0, 20])       # -> WaveOperators: a time-lapse,
    vols = [lfproc.deconvolve(f, operators=ops) for f in frames]         #    the operators built once
    fs.save("out/")                                                      # exactly what `lfproc refocus` writes

Results are frozen; their tags are the numbers the commands write in their sidecars (the same functions
make both), ``.records()`` are those sidecars, ``.save`` writes those files. Library manners: nothing is
printed (warnings go through :mod:`warnings` as :class:`lfproc.LfprocWarning`), nothing is written unless a
path is given (the decoder cache is opt-in: ``cache=True``), and errors name Python arguments.

Modules: ``_defaults`` (the commands' defaults), ``_checks`` (refocus parameters that make sense), ``_calibrate``
(the one grid fitting), ``_prepare`` (inputs checked against each other → a decoding setup), ``_setup`` (the
setup, which decodes captures), ``_read`` (a capture to a light field; how inputs are taken: files or arrays),
``_focal`` (focal stacks), ``_views`` (view stacks), ``_depth`` (depth maps), ``_deconvolve`` (a microscope's
volume by wave-optics deconvolution, :mod:`lfproc.wave`). Importing this package is light (numpy only).

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._checks import check_slices, check_view_coverage, check_z_step
from ._deconvolve import DEFAULT_SUPERRES, Volume, deconvolve, prepare_deconvolution
from ._defaults import DEFAULT_INTERPOLATION
from ._depth import depth_map
from ._focal import FocalStack, focal_stack
from ._calibrate import calibrate_white
from ._prepare import prepare_decoding
from ._read import read_light_field
from ._setup import DecodeSetup
from ._views import ViewStack, view_stack
