"""Test-wide settings.

Property tests (hypothesis) explore new random examples on every developer run. On CI (``CI`` set, as
``.ci/run`` is run) they are derandomized: the same examples every run, so a landing never depends on the
draw. Run ``pytest`` locally (or ``HYPOTHESIS_PROFILE=explore``) to keep searching for new counterexamples.
"""

import os

# Every code raised or noted during the tests must be in cnc_gym/error_codes.py (tests/test_error_codes.py):
# set before cnc_gym is imported, and inherited by the subprocesses the tests start, so an unregistered code
# fails at once.
os.environ["CNC_GYM_STRICT_CODES"] = "1"

from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "explore"))
