"""The MuJoCo plant's off-screen view: a picture where OpenGL can be had, a reason where it cannot."""

from __future__ import annotations

import numpy as np
import pytest

from cnc_gym.plant.mujoco import MujocoPlant
from cnc_gym.plant.mujoco_render import MachineView, open_gl_context


def test_no_gl_gives_a_reason_not_a_crash(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")
    context, reason = open_gl_context(64, 48)
    assert context is None and "disable" in reason
    view = MachineView(MujocoPlant("vmc-small-mujoco"), 64, 48)
    assert not view.available and view.reason
    with pytest.raises(RuntimeError, match="no off-screen OpenGL context"):
        view.draw(np.zeros((2, 3)), np.zeros((0, 3)), np.zeros(0), 0.02)
    view.close()


def test_draws_the_machine_the_path_and_the_trace_where_gl_is_available():
    plant = MujocoPlant("vmc-small-mujoco")
    view = MachineView(plant, 160, 120)
    if not view.available:
        pytest.skip(f"no off-screen OpenGL here: {view.reason}")
    try:
        t = np.linspace(0, 2 * np.pi, 100)
        path = np.stack((30 * np.cos(t), 30 * np.sin(t), 0 * t), axis=1)
        plain = view.draw(path, np.zeros((0, 3)), np.zeros(0), 0.02)
        traced = view.draw(path, path[:50], np.full(50, 0.04), 0.02)  # red: twice the tolerance
    finally:
        view.close()
    assert plain.shape == (120, 160, 3) and plain.dtype == np.uint8
    assert plain.std() > 10  # a scene, not a blank buffer
    red = (traced[..., 0] > 200) & (traced[..., 1] < 80)
    assert np.count_nonzero(red & ~((plain[..., 0] > 200) & (plain[..., 1] < 80))) > 20  # the trace
