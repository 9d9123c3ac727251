"""Make ``h4cm_helpers`` importable (the suite uses --import-mode=importlib)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
