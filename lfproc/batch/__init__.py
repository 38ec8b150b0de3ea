"""Batch processing: many captures, in parallel, resumable, locally or on a Dask cluster.

A batch is a list of :class:`Job` — plain, picklable data: one capture and what to make of it. The
same :func:`run_job` runs in this process, in a local process pool (:func:`run_local`) or on
dask.distributed workers (:func:`run_dask`); each worker reads its capture and writes its outputs
itself, atomically (:mod:`lfproc.atomic`), so no capture's pixels cross a process boundary (only the
calibrated white image, once per local worker process) and no reader ever sees a half-written file. A
deconvolution batch (``Job.deconvolve``) builds its operators once, in the process that starts it
(:func:`shared_operators`), and gives them to every worker (``operators=``: with each local process's start,
scattered once on Dask); workers never build them.

The manifest ``OUTDIR/lfproc-manifest.json`` (:class:`Manifest`) records, per capture, a fingerprint
(the capture file's size and modification time, those of the white image and grid file, the camera
file's text, the lfproc version and every parameter that shapes the outputs), the parameters, the
outputs (names relative to OUTDIR), status and error. A rerun skips captures whose fingerprint matches
a ``done`` entry whose outputs and sidecars all still exist, and redoes the rest. Each result is
recorded as it arrives (a line in a journal, folded into the manifest at the end), and a capture's
outputs appear together or not at all (:func:`lfproc.atomic.all_or_nothing`), so an interrupted or
killed batch resumes exactly where it stopped: the rerun does only the captures that were not recorded,
and none of those left an output behind.

One batch at a time may write to an OUTDIR: :func:`lock_outdir` holds an advisory lock on
``OUTDIR/.lfproc-batch.lock`` for the duration of a run; a lock left by a killed run is taken over.
Interrupts (SIGINT to the process group, SIGTERM) stop a batch within about a second: see
:mod:`._local` and :mod:`._signals`; docs/reliability.md lists every guarantee and its test.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._dask import run_dask
from ._jobs import Job, JobResult, expand_inputs
from ._local import run_local
from ._manifest import (JOURNAL_NAME, LOCK_NAME, MANIFEST_NAME, Manifest, lock_outdir, read_manifest,
                        remove_stale_partial_files)
from ._resources import BYTES_PER_SENSOR_PIXEL, PROCESS_BASE_BYTES, available_memory_bytes, default_workers
from ._worker import _GRID_SEEDS, decode_setup, run_job, shared_operators
