"""Test-wide settings.

Property tests (hypothesis) explore new random examples on every developer run. On CI (``CI`` set, as
``.ci/run`` is run) they are derandomized: the same examples every run, so a landing never depends on the
draw. Run ``pytest`` locally (or ``HYPOTHESIS_PROFILE=explore``) to keep searching for new counterexamples.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "explore"))

# The commands' "compiling the simulator" line goes to stderr once per process, before the first env step
# that compiles: in a test process it would land in whichever test steps first (a clean checkout's cache
# is cold), and tests that expect nothing on stderr would depend on their order. It is tested on its own
# (tests/test_rollout.py).
import cnc_gym.rollout  # noqa: E402

cnc_gym.rollout._announced = True
