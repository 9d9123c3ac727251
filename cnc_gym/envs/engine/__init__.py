"""The feed-rate task's engine: N episodes in the rows of a few arrays, stepped by one compiled call.

What the Feedrate envs (``cnc_gym/Feedrate-v0`` … v3) and their vector env run. The modules, each importing
only those before it (``layout ← specs ← bank ← step ← episode ← batch``, checked by
``tests/test_package_layout.py``):

- :mod:`~cnc_gym.envs.engine.layout`: the data layout. The per-step signals (:data:`SIGNALS`), the machine
  quantities, the look-ahead rows, the columns of the float and int state rows (``F_*``, ``I_*``) and of
  the step's outputs (:data:`OUTPUT_INFO_KEYS`), the config head of the bank (``CF_*``, ``CI_*``).
- :mod:`~cnc_gym.envs.engine.specs`: :class:`ObservationSpec` and :class:`RewardSpec`, the observation and
  the reward as declared records, turned into rows of floats for the step.
- :mod:`~cnc_gym.envs.engine.bank`: :class:`PackedProgram` (one program's controller, meter and planner
  tables), :class:`ProgramBank` (the config, the spec rows and every program in one float and one int
  array), the :class:`Planner` protocol, and the compiled accessors of the bank and of the scratch rows.
- :mod:`~cnc_gym.envs.engine.step`: the compiled step. Per env: the controller's periods, the servo plant,
  the in-position release, the contour error, the statistics, the reward, the end of the episode and the
  observation; or the reset of an env flagged for one.
- :mod:`~cnc_gym.envs.engine.episode`: whole episodes in compiled code: :class:`KnobRule` (a deployable
  policy's knob as data: a constant, or the planner's schedule) and the loop of the step under it.
- :mod:`~cnc_gym.envs.engine.batch`: :class:`FeedrateBatch`, which builds the bank, holds the state and the
  plant, calls the step (serial or in numba's threads; the modular step for a plant without compiled
  kernels) or the episode loop (:meth:`FeedrateBatch.run_rule`) and reads rewards, flags and infos back.

Data flow of a step: the env's actions → :meth:`FeedrateBatch.step` → ``run_serial``/``run_parallel``
(bank + state rows + plant arrays → the same state rows, the observation rows, the output columns) →
:meth:`FeedrateBatch.outcome` / :meth:`FeedrateBatch.gather` → the env's observation, reward, flags, info.
The observation and the reward are declared, not coded: a new env version defines its own specs (and, if
it needs one, adds a signal to the layout) without copying the step.
"""

from cnc_gym.envs.engine.bank import PackedProgram, Planner, ProgramBank
from cnc_gym.envs.engine.batch import INFO_KEYS, FeedrateBatch, step_needs_compiling
from cnc_gym.envs.engine.episode import KnobRule
from cnc_gym.envs.engine.layout import (
    LOOKAHEAD_ROWS,
    MACHINE_QUANTITIES,
    OUTPUT_INFO_KEYS,
    SIGNALS,
    machine_quantities,
)
from cnc_gym.envs.engine.specs import ObservationSpec, RewardSpec

__all__ = [
    "INFO_KEYS",
    "LOOKAHEAD_ROWS",
    "MACHINE_QUANTITIES",
    "OUTPUT_INFO_KEYS",
    "SIGNALS",
    "FeedrateBatch",
    "KnobRule",
    "ObservationSpec",
    "PackedProgram",
    "Planner",
    "ProgramBank",
    "RewardSpec",
    "machine_quantities",
    "step_needs_compiling",
]
