"""Put on PYTHONPATH by the reliability tests only: installs tests/faults.py's spec from LFPROC_FAULTS in
every Python process started with it (the lfproc command and its spawned batch workers)."""

import os
import sys

if os.environ.get("LFPROC_FAULTS"):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    import faults

    faults.install_from_env()
