"""Policies that drive cnc-gym envs: the baselines, the oracle and trained models.

A policy is ``reset(env)`` + ``act(observation, info) -> action`` (:class:`Policy`, the rollout's
protocol: :mod:`cnc_gym.rollout`); every one of them is measured by the same episode loop an RL agent
runs in, so baselines and agents compare. ``make_policy(spec)`` turns a command-line spec into a policy:

=====================  ======================================================================
``constant:<x>``       :class:`~.constant.ConstantOverride` at override x (1.0 = 100 %)
``classical``          :class:`~.classical.ClassicalPlanner`: the deployable look-ahead planner
                       (:mod:`cnc_gym.motion.planner`: machine parameters and its own servo model;
                       never runs the env)
``oracle``             :class:`~.oracle.OraclePlanner`: simulate-and-correct on copies of the
                       exact env; **an oracle**, not deployable
``nominal-oracle``     the same planner simulating the **nominal** machine, its schedule then run
                       open loop on the true plant (the benchmark's non-nominal tracks)
a path (``*.zip``)     :class:`~.model.ModelPolicy`, an SB3 model rebuilt without unpickling
``module:callable``    your own policy: ``callable`` in importable ``module`` is a Policy, or is
                       called with no arguments to make one (a class or a Python factory
                       function), or is a plain Python function ``act(observation, info) ->
                       action``; anything else (a built-in such as ``os:system``, a function of
                       other arguments, a value) is refused without being called
=====================  ======================================================================
"""

from __future__ import annotations

from cnc_gym.policies.base import Policy, override_action
from cnc_gym.policies.classical import ClassicalPlanner
from cnc_gym.policies.constant import ConstantOverride
from cnc_gym.policies.oracle import OraclePlanner
from cnc_gym.policies.spec import make_policy

__all__ = ["ClassicalPlanner", "ConstantOverride", "OraclePlanner", "Policy", "make_policy",
           "override_action"]
