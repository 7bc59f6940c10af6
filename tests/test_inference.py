"""Probabilistic inference: posterior, goal search, study."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from tolins.cli import main
from tolins.geometry.specs import CircularSocket
from tolins.geometry.tolerance import contains, pin_gaps, pins_inside
from tolins.inference import History, expected_success, find_goal, next_goal, sample_posterior
from tolins.inference.study import METHODS, SIGMA, SOCKET, StudyConfig, run_study

SPEC = SOCKET


def _rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)


def test_pins_inside_matches_contains() -> None:
    rng = _rng()
    eps = rng.normal(0, 0.12, size=(40, 2, 2))
    poses = rng.normal(0, [0.2, 0.2, 0.05], size=(30, 3))
    batch = pins_inside(SPEC, eps[:, None], poses[None]).all(-1)
    for n in range(len(eps)):
        bent = CircularSocket(2, 1, row_pitch=5.0, pin_offsets=eps[n])
        assert np.array_equal(batch[n], contains(bent, poses))


def test_pin_gaps_agree_with_pins_inside() -> None:
    rng = _rng(11)
    eps = rng.normal(0, 0.12, size=(20, 2, 2))
    poses = rng.normal(0, [0.2, 0.2, 0.05], size=(15, 3))
    gaps = pin_gaps(SPEC, eps[:, None], poses[None])
    assert gaps.shape == (20, 15, 2, 2)
    inside = np.linalg.norm(gaps, axis=-1) <= SPEC.clearance
    assert np.array_equal(inside, pins_inside(SPEC, eps[:, None], poses[None]))
    # At the nominal goal a pin's gap is its offset.
    assert np.allclose(pin_gaps(SPEC, eps, np.zeros(3)), eps)


def _contact_attempt(history: History, true: np.ndarray, goal: object) -> History:
    """``history`` plus an attempt at ``goal`` on workpiece ``true`` with exact contacts."""
    goal = np.asarray(goal, dtype=float)
    gaps = pin_gaps(SPEC, true, goal)
    inside = np.linalg.norm(gaps, axis=-1) <= SPEC.clearance
    bearings = np.where(inside, np.nan, np.arctan2(gaps[:, 1], gaps[:, 0]))
    return history.append(goal, bool(inside.all()), ~inside, bearings)


def test_bearings_locate_the_blocked_pin_after_one_failure() -> None:
    """Pin 0 bent 0.3 mm towards -y-x: one failed nominal attempt with its touch bearing
    points the posterior at the bend's direction, and the next goal inserts."""
    true = np.array([[-0.21, -0.21], [0.02, 0.0]])
    with_bearing = _contact_attempt(History.empty(), true, np.zeros(3))
    assert with_bearing.blocked.tolist() == [[True, False]]
    blocked_only = History(with_bearing.poses, with_bearing.inserted, with_bearing.blocked)
    posts = [sample_posterior(SPEC, h, SIGMA, 2000, _rng(9)) for h in (with_bearing, blocked_only)]

    def spread(p: object) -> float:
        """Weighted RMS of pin 0's offset angle around the bend's direction."""
        angle = np.arctan2(p.offsets[:, 0, 1], p.offsets[:, 0, 0])
        return float(np.sqrt(p.weights @ (angle - np.arctan2(-1, -1)) ** 2))

    assert spread(posts[0]) < 0.25 < spread(posts[1])
    result = find_goal(SPEC, posts[0], _rng(10))
    assert result.expected_success > 0.8
    assert pins_inside(SPEC, true, result.goal).all()


def test_posterior_concentrates_with_contact_evidence() -> None:
    true = np.array([[0.25, 0.0], [0.0, 0.0]])  # pin 0 bent 0.25 mm along +x
    history = History.empty()
    rng = _rng(1)
    for goal in ([0, 0, 0], [-0.1, 0, 0], [0.1, 0.05, 0], [0.0, -0.1, 0.02]):
        inside = pins_inside(SPEC, true, np.array(goal, dtype=float))
        history = history.append(goal, bool(inside.all()), ~inside)
    prior = sample_posterior(SPEC, History.empty(), SIGMA, 2000, rng)
    post = sample_posterior(SPEC, history, SIGMA, 2000, rng)

    def spread(p: object) -> float:
        return float(np.sqrt(p.weights @ np.sum((p.offsets - true) ** 2, axis=(1, 2))))

    assert spread(post) < 0.5 * spread(prior)
    mean = np.einsum("n,nij->ij", post.weights, post.offsets)
    assert mean[0, 0] > 0.15


def test_empty_history_gives_nominal_goal() -> None:
    result = next_goal(SPEC, History.empty(), SIGMA, _rng())
    assert np.array_equal(result.goal, np.zeros(3))
    assert 0.5 < result.expected_success < 0.7 and not result.discard


def test_unexplainable_history_gives_a_defined_answer() -> None:
    history = History(np.zeros((2, 3)), np.array([True, False]))
    post = sample_posterior(SPEC, history, SIGMA, 500, _rng())
    assert not post.explained and np.isfinite(post.weights).all()
    result = find_goal(SPEC, post, _rng())
    assert result.discard and result.expected_success == 0.0
    assert np.isfinite(result.goal).all()


def test_goal_search_beats_nominal_on_known_defect() -> None:
    history = History.empty().append([0, 0, 0], False)
    post = sample_posterior(SPEC, history, SIGMA, 2000, _rng(2))
    result = find_goal(SPEC, post, _rng(3))
    assert result.expected_success > float(expected_success(SPEC, post, np.zeros(3))[0]) + 0.1


def test_goal_searches_in_threads_find_what_they_find_alone() -> None:
    """pycma draws from numpy's global RNG: searches run in threads (π_φ* evaluations run
    two at a time) must not interleave their draws."""
    from concurrent.futures import ThreadPoolExecutor

    history = History.empty().append([0, 0, 0], False)
    post = sample_posterior(SPEC, history, SIGMA, 500, _rng(2))

    def search(seed: int) -> np.ndarray:
        return find_goal(SPEC, post, _rng(seed)).goal

    alone = [search(seed) for seed in range(8)]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(search, range(8)))
    assert all(np.array_equal(a, b) for a, b in zip(alone, threaded, strict=True))


def test_goal_moves_the_bent_pin_back() -> None:
    """Pin 1 (at y = +2.5 mm) bent 0.3 mm along +x: the goal moves it along -x."""
    true = np.array([[0.0, 0.0], [0.3, 0.0]])
    history = History.empty()
    for goal in ([0, 0, 0], [0, 0.15, 0], [0, -0.15, 0], [0.15, 0, 0]):
        inside = pins_inside(SPEC, true, np.array(goal, dtype=float))
        assert not inside.all()
        history = history.append(goal, False, ~inside)
    post = sample_posterior(SPEC, history, SIGMA, 2000, _rng(4))
    x, _, theta = find_goal(SPEC, post, _rng(5)).goal
    # Pin 1's x in its hole moves by x - 2.5 sin(theta).
    assert x - 2.5 * np.sin(theta) < -0.1


def test_tempering_explains_narrow_contact_histories() -> None:
    """Evidence that few prior samples satisfy is still explained (no discard)."""
    true = np.array([[-0.28, 0.12], [0.3, -0.2]])
    rng = _rng(6)
    history = History.empty()
    for goal in rng.normal(0, [0.15, 0.15, 0.03], size=(8, 3)):
        inside = pins_inside(SPEC, true, goal)
        history = history.append(goal, bool(inside.all()), ~inside)
    post = sample_posterior(SPEC, history, SIGMA, 300, _rng(7))
    assert post.explained and np.isfinite(post.weights).all()


def test_measurement_noise_softens_the_likelihood() -> None:
    """A failure measured at the nominal goal may have happened next to it: with pose noise
    the posterior keeps workpieces that the nominal goal itself would insert."""
    mass = {}
    for noise in (None, [0.1, 0.1, 0.0]):
        history = History(np.zeros((1, 3)), np.array([False]), measurement_noise=noise)
        post = sample_posterior(SPEC, history, SIGMA, 1000, _rng())
        assert post.explained
        mass[noise is None] = post.weights @ pins_inside(SPEC, post.offsets, np.zeros(3)).all(-1)
        assert np.isfinite(find_goal(SPEC, post, _rng()).goal).all()
    assert mass[True] == 0.0 and mass[False] > 0.2


def test_deterministic_for_a_seed() -> None:
    history = History.empty().append([0, 0, 0], False)
    a, b = (next_goal(SPEC, history, SIGMA, _rng(5)) for _ in range(2))
    assert np.array_equal(a.goal, b.goal) and a.expected_success == b.expected_success


def test_bad_histories_raise() -> None:
    with pytest.raises(ValueError, match="poses"):
        History(np.zeros((2, 2)), np.array([False, False]))
    with pytest.raises(ValueError, match="finite"):
        History(np.array([[np.nan, 0, 0]]), np.array([False]))
    with pytest.raises(ValueError, match="inserted"):
        History(np.zeros((1, 3)), np.array([1]))
    with pytest.raises(ValueError, match="blocked"):
        History(np.zeros((1, 3)), np.array([True]), np.array([[True, False]]))
    failed, blocked = np.array([False]), np.array([[True, False]])
    with pytest.raises(ValueError, match="without blocked"):
        History(np.zeros((1, 3)), failed, None, None, np.array([[0.5, np.nan]]))
    with pytest.raises(ValueError, match="shape"):
        History(np.zeros((1, 3)), failed, blocked, None, np.array([0.5, np.nan]))
    with pytest.raises(ValueError, match="not blocked"):
        History(np.zeros((1, 3)), failed, blocked, None, np.array([[0.5, 0.1]]))
    with pytest.raises(ValueError, match="inf"):
        History(np.zeros((1, 3)), failed, blocked, None, np.array([[np.inf, np.nan]]))
    unmeasured = History(np.zeros((1, 3)), failed, blocked, None, np.array([[np.nan, np.nan]]))
    assert np.isnan(unmeasured.bearings).all()
    with pytest.raises(ValueError, match="bearing_noise"):
        History.empty(bearing_noise=0.0)
    with pytest.raises(ValueError, match="every attempt or for none"):
        History.empty().append([0, 0, 0], False, [True, False], [0.1, np.nan]).append(
            [0, 0, 0], False, [True, False]
        )


def test_tiny_study_schema_ranking_and_worker_independence() -> None:
    config = StudyConfig(samples=12, seed=3, particles=300, workers=1, kind_samples=2)
    result = run_study(config)
    data = result.to_json()
    assert set(data) == {"nominal_insertable", "impossible", "methods", "kinds"}
    assert set(data["methods"]) == set(config.methods)
    for figures in data["methods"].values():
        assert set(figures) == {"success_within_10", "mean_attempts"}
    m = data["methods"]
    assert m["oracle"]["success_within_10"] >= m["inference"]["success_within_10"]
    assert m["inference"]["success_within_10"] >= m["nominal"]["success_within_10"]
    two = run_study(StudyConfig(samples=12, seed=3, particles=300, workers=2, kind_samples=2))
    assert all(np.array_equal(result.attempts[k], two.attempts[k]) for k in config.methods)
    assert two.to_json()["kinds"] == data["kinds"]


def test_contact_bearings_save_attempts() -> None:
    """On the same workpieces, each level of evidence inserts in fewer attempts."""
    methods = ("inference", "inference_blocked", "inference_contact")
    result = run_study(
        StudyConfig(samples=40, seed=2, particles=300, workers=1, methods=methods, kinds=("bent",))
    )
    attempts = {m: result.attempts[m] for m in methods}
    both = (attempts["inference_contact"] > 0) & (attempts["inference_blocked"] > 0)
    assert attempts["inference_contact"][both].sum() < attempts["inference_blocked"][both].sum()
    assert result.summary("inference_contact")["mean_attempts"] < 1.7
    assert result.summary("inference")["mean_attempts"] > 1.7


def test_a_methods_result_does_not_depend_on_the_other_methods() -> None:
    """Each method draws from its own stream, keyed by the method, not by its position."""
    both = run_study(
        StudyConfig(
            samples=10,
            seed=4,
            particles=200,
            workers=1,
            methods=("random", "inference"),
            kinds=("bent",),
        )
    )
    alone = run_study(
        StudyConfig(
            samples=10, seed=4, particles=200, workers=1, methods=("inference",), kinds=("bent",)
        )
    )
    assert np.array_equal(both.attempts["inference"], alone.attempts["inference"])
    first = run_study(
        StudyConfig(samples=10, seed=4, workers=1, methods=("random",), kinds=("bent",))
    )
    assert np.array_equal(both.attempts["random"], first.attempts["random"])


def test_cli_smoke(tmp_path, capsys) -> None:
    out, plot = tmp_path / "study.json", tmp_path / "study.png"
    code = main(
        [
            *("infer-study", "--samples", "4", "--particles", "200", "--workers", "1"),
            *("--kind-samples", "1"),
            *("--json", str(out), "--plot", str(plot)),
        ]
    )
    assert code == 0
    assert "inference" in capsys.readouterr().out
    assert set(json.loads(out.read_text())["methods"]) >= {"inference", "random", "oracle"}
    assert plot.stat().st_size > 1000


def test_cli_help_lists_every_method(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["infer-study", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert all(method in help_text for method in METHODS)


def test_physics_contact_evidence_matches_geometry() -> None:
    from tolins.inference.physics import physics_attempt

    rng = _rng(8)
    eps = np.array([[0.05, -0.1], [0.25, 0.1]])
    workpiece = CircularSocket(2, 1, row_pitch=5.0, pin_offsets=eps)
    for goal in rng.normal(0, [0.12, 0.12, 0.03], size=(6, 3)):
        inserted, blocked, bearings = physics_attempt(workpiece, goal)
        gaps = pin_gaps(SPEC, eps, goal)
        inside = np.linalg.norm(gaps, axis=-1) <= SPEC.clearance
        assert inserted == inside.all()
        assert inserted or np.array_equal(blocked, ~inside)
        assert np.array_equal(np.isfinite(bearings), blocked)
        # Touch points sit on the 16-gon hole's rim: the bearing is the gap's direction
        # within about half a facet (π/16).
        expected = np.arctan2(gaps[:, 1], gaps[:, 0])
        error = np.angle(np.exp(1j * (bearings - expected)))[blocked]
        assert np.all(np.abs(error) < 0.2)


# --- the study on parts whose pins bend ---------------------------------------------------


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"pins": "soft"}, "pins='soft'; allowed: 'rigid', 'elastic-plastic'"),
        ({"pins": "elastic-plastic", "physics": True, "kinds": (), "pin_material": "gold"}, "gold"),
        ({"pins": "elastic-plastic", "kinds": ()}, "allowed: physics=True"),
        ({"pins": "elastic-plastic", "physics": True}, "allowed: () or ('bent',)"),
    ],
)
def test_bad_pin_settings_of_the_study_are_one_line(settings, message) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        StudyConfig(**settings)


def test_an_attempt_meets_the_part_as_the_last_left_it_when_kept() -> None:
    """A part bent by a sideways drag (its pins 0.5 mm in their holes) stays bent for the
    next attempt that keeps it, which the bend blocks at the nominal goal, where a straight
    part inserts; not kept, the part is straight again."""
    from tolins.inference.physics import AttemptBatch
    from tolins.paper import A_MAX

    pins = StudyConfig(pins="elastic-plastic", physics=True, kinds=()).elastic_pins()
    batch = AttemptBatch(SOCKET, slots=1, num_threads=1, pins=pins)
    physics, slot = batch.physics, np.array([0])
    physics.reset(slot, np.array([[0.0, 0.0, 0.0, 0.05]]))
    while physics.step(slot, np.array([[0.0, 0.0, 0.0, -0.6]])).pose[0, 3] > -0.5:
        pass
    for _ in range(4):
        state = physics.step(slot, np.array([[A_MAX[0], A_MAX[1], 0.0, 0.0]]))
    assert np.hypot(*state.pin_bend[0].T).max() > pins.damage_threshold
    nominal = [(SOCKET, np.zeros(3))]
    ((inserted, blocked, _),) = batch.attempts(nominal, slots=[0], keep_part=[True])
    assert not inserted and blocked.any()
    assert np.array_equal(batch.bend(0), state.pin_bend[0])  # a push bends it no further
    ((inserted, _, _),) = batch.attempts(nominal, slots=[0], keep_part=[False])
    assert inserted and not batch.bend(0).any()
    batch.close()


def test_the_studys_straight_pushes_bend_no_pin_for_good(monkeypatch) -> None:
    """The study's attempts push the part straight down at a goal: the pins that meet the
    board's top press along their axis (Euler's load is 20 times the servos' 5 N), and no
    part is left damaged (elastic compliance may still let in a pin a rigid one would not:
    outcomes may differ from rigid pins', benchmarks/README.md)."""
    config = StudyConfig(samples=4, particles=200, workers=1, physics=True, kinds=())
    config = dataclasses.replace(config, methods=("inference_contact", "random"))
    bending = run_study(dataclasses.replace(config, pins="elastic-plastic"))
    for method in config.methods:
        assert len(bending.damaged[method]) == 4 and not bending.damaged[method].any()
    figures = bending.to_json()
    assert figures["pins"] == {"model": "elastic-plastic", "material": "phosphor_bronze"}
    from tolins.inference import study

    monkeypatch.setattr(study, "PART_SLOTS", 3)  # the runs a few at a time: the same results
    grouped = run_study(dataclasses.replace(config, pins="elastic-plastic"))
    for method in config.methods:
        assert np.array_equal(grouped.attempts[method], bending.attempts[method])
    assert figures["methods"]["random"]["damaged"] == 0.0
    assert set(run_study(config).to_json()["methods"]["random"]) == {
        "success_within_10",
        "mean_attempts",
    }
