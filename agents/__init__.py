"""cnc-gym's learning code: training RL agents on the Feedrate envs (installed as ``cnc_gym_agents``).

==========================  ==========================================================================
:mod:`.training`            the validated training config and the PPO / PPO-Lagrangian training loop
:mod:`.lagrangian`          PPO-Lagrangian as a small layer over Stable-Baselines3
==========================  ==========================================================================

It depends on :mod:`cnc_gym` only, and nothing in :mod:`cnc_gym` depends on it: the baselines, the oracle
and the loading of trained models are :mod:`cnc_gym.policies`, and the episode loop that measures them all
is :mod:`cnc_gym.rollout`.
"""
