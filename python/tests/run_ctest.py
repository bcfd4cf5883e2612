"""ctest's entry to the Python tests: runs pytest on python/tests, or reports the test
skipped (exit 77) when a package it needs is not installed."""
import importlib.util
import sys
from pathlib import Path

missing = [m for m in ("numpy", "pytest", "torch") if importlib.util.find_spec(m) is None]
if missing:
    print("SKIPPED: the Python tests need " + ", ".join("python3-" + m for m in missing) +
          " (scripts/install-deps.sh installs them)")
    sys.exit(77)

import pytest  # noqa: E402

here = Path(__file__).resolve().parent
sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", str(here)] + sys.argv[1:]))
