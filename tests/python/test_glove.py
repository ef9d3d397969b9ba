"""The simulated users' data glove in the core (handsim.Glove) against the Python glove it replaced, on made-up
users, poses and shapes; and its errors on bad input."""
import math

import numpy as np
import pytest

import handsim
from handsim import users as U
from handsim.quat import axis_angle, quat_mul

RIGHT, LEFT = handsim.Handedness.RIGHT, handsim.Handedness.LEFT


class ReferenceGlove:
    """The Python glove of handsim.users before the core took it over (numpy's generator draws the variates
    one call at a time, as it did)."""

    def __init__(self, handedness, noise, scale, dt, seed):
        self.handedness, self.noise, self.scale = handedness, noise, scale
        self.rng = np.random.default_rng(seed)
        self.ou = [self._ou(7, noise["finger_drift"], 1.0, dt), self._ou(3, noise["palm_drift"], 0.7, dt),
                   self._ou(1, noise["yaw_drift"], 1.0, dt)]

    def _ou(self, n, sigma, tau, dt):
        a = math.exp(-dt / tau)
        x = self.rng.normal(0, sigma, n) if sigma > 0 else np.zeros(n)
        return {"sigma": sigma, "a": a, "b": sigma * math.sqrt(1 - a * a), "x": x}

    def _step(self, ou):
        if ou["sigma"] > 0:
            ou["x"] = ou["a"] * ou["x"] + ou["b"] * self.rng.normal(0, 1, ou["x"].shape)
        return ou["x"]

    def frame(self, palm, curl, opposition, spread, tracked):
        drift, palm_off, yaw = (self._step(ou) for ou in self.ou)
        white = self.rng.normal(0, self.noise["finger_noise"], 7)
        jitter = self.rng.normal(0, self.noise["palm_noise"], 3)
        if not tracked:
            return None
        n = drift + white
        pose = np.asarray(palm, float).copy()
        pose[:3] += palm_off + jitter
        q = quat_mul(axis_angle([0, 1, 0], float(yaw[0])), pose[3:])
        pose[3:] = q / np.linalg.norm(q)
        return handsim.make_hand_frame(self.handedness, pose, curl=np.clip(np.asarray(curl) + n[:5], 0.0, 1.0),
                                       thumb_opposition=float(np.clip(opposition + n[5], 0.0, 1.0)),
                                       spread=float(np.clip(spread + 0.5 * n[6], -0.5, 1.0)), scale=self.scale)


def made_up_noise(rng, zero=()):
    noise = {"finger_noise": rng.uniform(0.005, 0.05), "finger_drift": rng.uniform(0, 0.05),
             "palm_noise": rng.uniform(0, 0.003), "palm_drift": rng.uniform(0, 0.005),
             "yaw_drift": rng.uniform(0, 0.1)}
    return {k: 0.0 if k in zero else float(v) for k, v in noise.items()}


def core_glove(handedness, noise, scale, dt, seed):
    """handsim.Glove fed from its own generator the way handsim.users.SeededGlove feeds it (variates drawn ahead)."""
    rng = np.random.default_rng(seed)
    z = rng.standard_normal(100_000)
    used = [0]

    def take(n):
        used[0] += n
        return z[used[0] - n:used[0]]

    glove = handsim.Glove(handedness, scale=scale, dt=dt, **noise)
    glove.start(take(glove.start_normals))
    return glove, take


@pytest.mark.parametrize("zero", [(), ("finger_drift",), ("palm_drift", "yaw_drift"),
                                  ("finger_drift", "palm_drift", "yaw_drift")])
def test_core_glove_gives_the_python_glove_frames(zero):
    rng = np.random.default_rng(len(zero))
    for trial in range(6):
        handedness = (RIGHT, LEFT)[trial % 2]
        noise, scale, dt = made_up_noise(rng, zero), float(rng.uniform(0.85, 1.15)), 1 / float(rng.choice([30, 60, 90]))
        ref = ReferenceGlove(handedness, noise, scale, dt, [trial, 7919])
        glove, take = core_glove(handedness, noise, scale, dt, [trial, 7919])
        for i in range(120):
            q = rng.normal(size=4)
            palm = np.concatenate([rng.normal(0, 0.3, 3), q / np.linalg.norm(q)])
            curl, opposition, spread = rng.uniform(-0.1, 1.1, 5), float(rng.uniform(-0.1, 1.1)), float(rng.uniform(-0.6, 1.1))
            tracked = bool(i % 17 != 5)
            want = ref.frame(palm, curl, opposition, spread, tracked)
            got = glove.frame(palm, curl, opposition, spread, tracked, take(glove.frame_normals))
            if want is None:
                assert not got.tracked and not got.valid.any()
                continue
            # Equal to the bit on x86-64 (numpy's dot sums with fused multiply-adds there, as the core does);
            # 1e-12 leaves room for a numpy whose dot sums otherwise.
            assert got.handedness == want.handedness
            assert np.abs(got.positions - want.positions).max() <= 1e-12
            assert np.abs(got.orientations - want.orientations).max() <= 1e-12
            np.testing.assert_array_equal(got.radii, want.radii)
            assert got.valid.all()
        drift = np.concatenate([ou["x"] for ou in ref.ou])
        assert np.abs(glove.drift - drift).max() <= 1e-15


def test_users_glove_draws_like_the_python_glove():
    """handsim.users.SeededGlove (variates drawn ahead in blocks) takes them in the reference glove's order, over more
    frames than one block holds."""
    user = U.draw_user(4, "open", 2)
    noise = {k: getattr(user, k) for k in ("finger_noise", "finger_drift", "palm_noise", "palm_drift", "yaw_drift")}
    ref = ReferenceGlove(RIGHT, noise, user.scale, 1 / 60, [user.seed, 7919, 0])
    glove = U.SeededGlove(user, RIGHT, 0, 1 / 60)
    palm = np.array([0.0, 0.3, 0.1, 0.0, 0.0, 0.0, 1.0])
    for i in range(2 * U.SeededGlove.NORMALS_BLOCK // glove.core.frame_normals + 3):
        t = i / 60
        want = ref.frame(palm, U.PINCH.curl, U.PINCH.thumb_opposition, U.PINCH.spread, glove.tracked(t))
        got = glove.frame(t, palm, U.PINCH)
        assert (want is None) == (not got.tracked)
        if want is not None:
            assert np.abs(got.positions - want.positions).max() <= 1e-12


def test_untracked_frame():
    f = handsim.untracked_frame(LEFT)
    assert f.handedness == LEFT and not f.tracked and not f.valid.any()


def test_bad_input_names_the_argument_and_leaves_the_glove_as_it_was():
    glove = handsim.Glove(RIGHT, finger_noise=0.01, finger_drift=0.02, palm_drift=0.001, yaw_drift=0.02)
    glove.start(np.full(glove.start_normals, 0.5))
    before = glove.drift.copy()
    palm, curl, z = [0, 0.3, 0, 0, 0, 0, 1], [0.2] * 5, np.ones(glove.frame_normals)
    for args, name in [((palm, curl, 0.5, 0.0, True, z[:-1]), "z"),
                       ((palm, curl, 0.5, 0.0, True, np.where(np.arange(z.size) == 3, np.nan, z)), "z[3]"),
                       (([0, 0.3, 0, 0, 0, 0, 2], curl, 0.5, 0.0, True, z), "palm"),
                       (([0, 0.3, 0, 0, 0, 0], curl, 0.5, 0.0, True, z), "palm"),
                       ((palm, [0.2] * 4, 0.5, 0.0, True, z), "curl"),
                       ((palm, [0.2, np.inf, 0, 0, 0], 0.5, 0.0, True, z), "shape.curl[1]"),
                       ((palm, curl, math.nan, 0.0, True, z), "shape.thumb_opposition"),
                       ((palm, curl, 0.5, 0.0, None, z), "tracked")]:
        with pytest.raises((ValueError, TypeError, handsim.Error), match=name.replace("[", r"\[")):
            glove.frame(*args)
        np.testing.assert_array_equal(glove.drift, before)
    for kwargs, name in [({"finger_noise": -1.0}, "noise.finger_noise"), ({"yaw_drift": math.inf}, "noise.yaw_drift"),
                         ({"scale": 0.0}, "scale"), ({"dt": 0.0}, "dt")]:
        with pytest.raises((ValueError, handsim.Error), match=name):
            handsim.Glove(RIGHT, **kwargs)
    with pytest.raises(ValueError, match="z"):
        glove.start(np.zeros(glove.start_normals + 1))
    np.testing.assert_array_equal(glove.drift, before)
    assert glove.frame(palm, curl, 0.5, 0.0, True, z).tracked
