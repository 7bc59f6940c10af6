"""Inference with the defect model: pitch error, burrs and blocked holes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tolins.geometry.specs import CircularSocket
from tolins.geometry.tolerance import moved_pins, pins_inside
from tolins.inference.goal import next_goal
from tolins.inference.history import History
from tolins.inference.posterior import (
    DefectModel,
    defect_parts,
    sample_defect_posterior,
    sample_posterior,
)
from tolins.inference.report import format_kinds_markdown, format_markdown
from tolins.inference.study import (
    DEFECT_MODEL,
    SIGMA,
    SOCKET,
    StudyConfig,
    geometry_outcome,
    insertable,
    insertion_margin,
    kind_workpieces,
    run_study,
)

#: Pin 1 bent 0.15 mm in x and the row pitch 6 % long (the pins ±0.15 mm in y): blocked at
#: the nominal goal, inserted 0.075 mm to -x.
PITCHED = dataclasses.replace(
    SOCKET, pin_offsets=((0.0, 0.0), (0.15, 0.0)), pin_pitch_scale=(1.0, 1.06)
)
#: Pin 0 bent 0.1 mm in x with a 0.15 mm burr (its clearance 0.05 mm): blocked at the
#: nominal goal, inserted about 0.1 mm to -x.
BURRED = dataclasses.replace(SOCKET, pin_offsets=((0.1, 0.0), (0.0, 0.0)), pin_burrs=(0.15, 0.0))


def infer(spec, *, contact=True, particles=400, attempts=10, seed=0, model=DEFECT_MODEL):
    """The defect model's inference on workpiece ``spec`` with geometry outcomes: the
    attempt that inserted (0: none), whether it said not insertable, the last result and
    the history."""
    outcome = geometry_outcome(spec.offsets, spec)
    rng = np.random.default_rng(seed)
    history = History.empty()
    found = None
    for attempt in range(1, attempts + 1):
        found = next_goal(SOCKET, history, SIGMA, rng, n_samples=particles, model=model)
        if found.not_insertable:
            return 0, True, found, history
        inside, bearings = outcome(found.goal)
        if inside.all():
            return attempt, False, found, history
        history = history.append(
            found.goal, False, ~inside if contact else None, bearings if contact else None
        )
    return 0, False, found, history


def test_pitch_error_is_explained_and_the_next_goal_inserts() -> None:
    assert insertable(PITCHED) and not pins_inside(PITCHED, PITCHED.offsets, np.zeros(3)).all()
    attempt, verdict, _, history = infer(PITCHED)
    assert 1 < attempt <= 4 and not verdict
    # The posterior's pins (bends plus pitch error) sit where the true pins are.
    posterior = sample_defect_posterior(
        SOCKET, history, DEFECT_MODEL, 400, np.random.default_rng(1)
    )
    truth = PITCHED.pin_centers - SOCKET.hole_centers
    mean = np.einsum("n,nij->ij", posterior.weights, posterior.offsets)
    assert np.abs(mean - truth).max() < 0.08
    assert posterior.blocked < 0.95


def test_burr_is_explained_and_the_next_goal_inserts() -> None:
    assert insertable(BURRED) and not pins_inside(BURRED, BURRED.offsets, np.zeros(3)).all()
    attempt, verdict, _, history = infer(BURRED)
    assert attempt > 1 and not verdict
    posterior = sample_defect_posterior(
        SOCKET, history, DEFECT_MODEL, 400, np.random.default_rng(1)
    )
    assert posterior.burrs.shape == (400, 2)
    assert posterior.weights @ posterior.burrs[:, 0] > posterior.weights @ posterior.burrs[:, 1]


def test_blocked_hole_is_reported_not_insertable_within_the_budget() -> None:
    for spec in kind_workpieces("blocked", 3, seed=5):
        attempt, verdict, found, history = infer(spec)
        assert attempt == 0 and verdict and found.not_insertable
        assert len(history) < 10 and found.blocked > DEFECT_MODEL.blocked_prior


def test_nominal_and_insertable_workpieces_are_never_reported_not_insertable() -> None:
    attempt, verdict, found, _ = infer(SOCKET)
    assert (attempt, verdict, found.not_insertable) == (1, False, False)
    for kind in ("pitch", "burr"):
        for seed, spec in enumerate(kind_workpieces(kind, 4, seed=7)):
            attempt, verdict, _, _ = infer(spec, seed=seed)
            # "Not insertable" means an expected success below 2 %: a feasible region as
            # narrow as 0.01 mm may be given up, a wider one is not.
            if insertion_margin(spec) > 0.03:
                assert attempt > 0 and not verdict
            if not insertable(spec):
                assert attempt == 0


def test_bent_model_is_unchanged_by_the_defect_model() -> None:
    """Without ``model`` next_goal is the bent-pin inference; its posterior has no burrs."""
    history = History.empty().append([0.0, 0.0, 0.0], False, [True, False], [0.0, np.nan])
    bent = sample_posterior(SOCKET, history, SIGMA, 50, np.random.default_rng(0))
    assert bent.burrs is None and bent.blocked == 0.0
    a = next_goal(SOCKET, history, SIGMA, np.random.default_rng(0), n_samples=100)
    b = next_goal(SOCKET, history, SIGMA, np.random.default_rng(0), n_samples=100)
    np.testing.assert_array_equal(a.goal, b.goal)
    assert not a.not_insertable and a.blocked == 0.0
    # A model with neither pitch error, burrs nor blocked holes is a bent-pin model.
    only_bends = DefectModel(SIGMA)
    found = next_goal(SOCKET, history, SIGMA, np.random.default_rng(0), model=only_bends)
    assert found.blocked == 0.0 and found.expected_success > 0.5


#: A grasp error's prior (x, y, yaw std: mm, mm, rad), as an env's ``grasp_error``.
GRASP = (0.5, 0.5, 0.02)


def grasped(error: np.ndarray) -> CircularSocket:
    """The nominal workpiece held ``error`` ``[dx, dy, dyaw]`` off in the hand, as bends."""
    latent = np.zeros((1, 3 * SOCKET.n_pins + 5))
    latent[0, -3:] = error
    offsets, _ = defect_parts(SOCKET, latent)
    return dataclasses.replace(SOCKET, pin_offsets=tuple(map(tuple, offsets[0])))


def test_a_grasp_error_moves_every_pin_as_the_part_held_off_in_the_hand() -> None:
    """Pin i at ``R(dψ) h_i + (dx, dy)``: the part's rigid motion, with the pitch error too."""
    error = np.array([0.3, -0.2, 0.04])
    spec = grasped(error)
    expected = moved_pins(SOCKET.hole_centers, error) - SOCKET.hole_centers
    np.testing.assert_allclose(spec.offsets, expected, atol=1e-15)
    # A pitch error scales the pins, which the grasp's yaw then turns with the part.
    latent = np.zeros((1, 3 * SOCKET.n_pins + 5))
    latent[0, 2 * SOCKET.n_pins : 2 * SOCKET.n_pins + 2] = 0.0, 0.1
    latent[0, -3:] = error
    offsets, burrs = defect_parts(SOCKET, latent)
    pitched = SOCKET.hole_centers * [1.0, 1.1]
    np.testing.assert_allclose(
        offsets[0], moved_pins(pitched, error) - SOCKET.hole_centers, atol=1e-15
    )
    assert np.all(burrs == 0.0)
    # Without a grasp error the latent has no grasp coordinates.
    assert (
        len(DefectModel(SIGMA).scales(2)) == 8
        and len(DefectModel(SIGMA, grasp_sigma=GRASP).scales(2)) == 11
    )


def test_a_grasp_error_is_found_from_failed_attempts_alone() -> None:
    """Outcomes only (no contact evidence): the grasp-error prior puts every pin's offset in
    one common motion and searches it, so it inserts workpieces held off in the hand that
    the bent-pin prior gives up on (it explains a failure by independent bends, under
    which no goal is likely enough)."""
    rng = np.random.default_rng(1)
    errors = np.clip(rng.normal(0.0, 1.0, (24, 3)), -3.0, 3.0) * GRASP
    errors = [
        e for e in errors if not pins_inside(grasped(e), grasped(e).offsets, np.zeros(3)).all()
    ]
    assert len(errors) >= 20  # the nominal goal fails on these
    grasp, bent = DefectModel(0.0, grasp_sigma=GRASP), DefectModel(GRASP[0])
    found = {
        name: [
            infer(grasped(e), contact=False, model=model, seed=k)[0] > 0
            for k, e in enumerate(errors)
        ]
        for name, model in (("grasp", grasp), ("bent", bent))
    }
    assert sum(found["grasp"]) >= 0.3 * len(errors)
    assert sum(found["bent"]) <= 0.1 * len(errors)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"sigma": 0.0}, "something must move the pins"),
        ({"sigma": 0.1, "grasp_sigma": (0.1, 0.1)}, "three stds"),
        ({"sigma": 0.1, "grasp_sigma": (0.1, -0.1, 0.0)}, "three stds"),
        ({"sigma": -0.1}, "sigma=-0.1; allowed: ≥ 0"),
    ],
)
def test_defect_model_refuses_bad_priors(options, message) -> None:
    with pytest.raises(ValueError, match=message):
        DefectModel(**options)


def test_study_reports_each_kind() -> None:
    config = StudyConfig(
        samples=3,
        seed=1,
        particles=200,
        workers=1,
        kind_samples=3,
        methods=("inference_contact", "nominal", "oracle"),
    )
    result = run_study(config)
    data = result.to_json()
    assert list(data["kinds"]) == ["bent", "pitch", "burr", "blocked"]
    assert data["kinds"]["bent"]["methods"]["nominal"] == {
        **data["methods"]["nominal"],
        "not_insertable": 0.0,
    }
    blocked = data["kinds"]["blocked"]
    assert blocked["impossible"] == 1.0 and blocked["workpieces"] == 3
    assert blocked["methods"]["inference_contact"]["not_insertable"] == 1.0
    assert all(m["success_within_10"] == 0.0 for m in blocked["methods"].values())
    for kind in ("pitch", "burr"):
        figures = data["kinds"][kind]["methods"]
        assert (
            figures["inference_contact"]["success_within_10"]
            >= (figures["nominal"]["success_within_10"])
        )
        assert figures["inference_contact"]["success_within_10"] <= (
            1 - data["kinds"][kind]["impossible"]
        )
    markdown = format_markdown(data)
    assert "| blocked | 3 | 100.0% | inference_contact | 0.0% | 0.000 | 100.0% |" in markdown
    # An earlier run's JSON (no kinds) renders as before.
    old = {key: data[key] for key in ("nominal_insertable", "impossible", "methods")}
    assert format_kinds_markdown(old) == "" and "kind" not in format_markdown(old)


def test_physics_study_per_kind() -> None:
    """MuJoCo outcomes: burred workpieces insert, blocked ones (either hole) are reported
    not insertable and never insert."""
    config = StudyConfig(
        samples=1,
        seed=0,
        particles=200,
        workers=1,
        kind_samples=4,
        physics=True,
        kinds=("burr", "blocked"),
        methods=("inference_contact",),
    )
    result = run_study(config)
    blocked = result.kinds["blocked"]
    holes = {spec.blocked_holes for spec in kind_workpieces("blocked", 4, 0)}
    assert holes == {(0,), (1,)}
    assert not blocked["attempts"]["inference_contact"].any()
    assert blocked["not_insertable"]["inference_contact"].all()
    burr = result.kinds["burr"]
    assert (burr["attempts"]["inference_contact"] > 0).sum() >= burr["insertable"].sum() - 1


def test_bench_study_stage_reports_the_kinds() -> None:
    from tolins.bench.pipeline.profiles import PROFILES
    from tolins.bench.pipeline.settings import study_settings

    quick = study_settings(PROFILES["quick"], "mujoco")
    assert quick.kinds == ("bent", "pitch", "burr", "blocked") and quick.kind_samples == 12
    assert study_settings(PROFILES["tiny"], "mujoco").kind_samples <= PROFILES["tiny"].study_samples
