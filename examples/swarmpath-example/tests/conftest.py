"""The example's tests import the package as installed (pip install -e .), or from src/."""

import sys
from pathlib import Path

try:
    import swarmpath_example  # noqa: F401
except ImportError:  # a checkout that did not install it
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
