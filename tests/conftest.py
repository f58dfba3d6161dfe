"""Settings every test process shares."""

import os

# Backend "auto" runs the numpy reference for kernels not compiled yet (the suites' objectives
# are not in the install's warm-up) and would start a background compile of them from the tests'
# processes, outliving the run: the tests keep the reference and start none
# (tests/test_compiled_background.py turns it on for its own subprocesses).
os.environ.setdefault("SWARMPATH_BACKGROUND_COMPILE", "0")
