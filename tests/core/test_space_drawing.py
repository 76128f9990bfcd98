"""What a plant in space says to draw: three views, its chain in 3-D, targets in space; no robot names."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.core.drawing import SPACE_VIEWS, SpaceDrawing, ViewProjection
from mt_widgets.core.targets import ConveyorTarget, SpacePointTarget
from mt_widgets.core.workspace import Cuboid


def test_the_arm_is_drawn_in_three_views_framing_its_whole_chain():
    skill = SKILLS["ur5-reach"]
    drawing = skill.drawing()
    assert isinstance(drawing, SpaceDrawing) and tuple(v.name for v in drawing.views) == SPACE_VIEWS
    states = np.vstack([skill.query_states(seed=seed) for seed in range(5)] + [skill.start[None]])
    chain = skill.sketch(states).chain
    assert chain.shape == (len(states), 8, 3)
    np.testing.assert_allclose(chain[:, -1], skill.end_effector(states)[0])        # the chain ends at the tool
    np.testing.assert_allclose(chain[:, 0], np.broadcast_to(drawing.base, (len(states), 3)))
    assert np.all(drawing.bounds.contains(chain.reshape(-1, 3)))
    for name in SPACE_VIEWS:
        extent = drawing.extent(name)
        flat = drawing.projection(name).project(chain.reshape(-1, 3))
        assert np.all((flat[:, 0] >= extent.xlim[0]) & (flat[:, 0] <= extent.xlim[1]))
        assert np.all((flat[:, 1] >= extent.ylim[0]) & (flat[:, 1] <= extent.ylim[1]))
    # the table top is the scene, at the base's height
    assert np.all(drawing.surfaces[0][:, 2] == drawing.base[2])


def test_the_orthographic_views_keep_the_components_a_person_draws_and_the_perspective_one_recedes():
    top, side = ViewProjection("top"), ViewProjection("side")
    point = np.array([0.4, -0.2, 0.3])
    np.testing.assert_array_equal(top.project(point), [0.4, -0.2])
    np.testing.assert_array_equal(side.project(point), [0.4, 0.3])
    camera = ViewProjection("perspective", azimuth_deg=0.0, elevation_deg=0.0, distance=2.0)
    right, up, forward = camera.camera()
    np.testing.assert_allclose(forward, [-1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(camera.project([0.0, 0.3, 0.2]), [0.3, 0.2], atol=1e-15)   # at the centre: true size
    far, near = camera.project([[-1.0, 0.3, 0.0], [1.0, 0.3, 0.0]])
    assert far[0] == pytest.approx(0.3 * 2 / 3) and near[0] == pytest.approx(0.3 * 2 / 1)  # smaller further away
    with pytest.raises(ValueError, match="points: expected points in front of the camera"):
        camera.project([3.0, 0.0, 0.0])


def test_the_conveyor_skill_draws_its_belt_and_its_target_moves_with_the_phase():
    skill = SKILLS["ur5-conveyor"]
    drawing = skill.drawing()
    belt = drawing.surfaces[1]
    assert np.ptp(belt[:, 1]) > 1.0 and np.ptp(belt[:, 2]) == 0   # a flat strip along y
    target = skill.target
    assert isinstance(target, ConveyorTarget) and target.noun == "part on the conveyor"
    np.testing.assert_allclose(target.at([0.0, 0.4]), [[0.45, -0.25, 0.10], [0.45, 0.15, 0.10]])
    np.testing.assert_allclose(target.at(0.2), skill.plant.conveyor.part_position(0.2))
    assert target.distance([0.45, 3.0, 0.4]) == pytest.approx(0.3)
    assert skill.target_shape().points.shape == (2, 3)


def test_space_targets_and_drawings_refuse_bad_input_by_name():
    target = SpacePointTarget((0.55, -0.1, 0.1))
    assert target.distance([[0.55, -0.1, 0.4]]).tolist() == pytest.approx([0.3])
    with pytest.raises(ValueError, match=r"point: expected shape \(3\)"):
        SpacePointTarget((0.5, 0.1))
    with pytest.raises(ValueError, match=r"positions: expected shape \(3\)"):
        target.distance([0.5, 0.1])
    with pytest.raises(ValueError, match="name: expected one of"):
        ViewProjection("front")
    with pytest.raises(ValueError, match="views: expected a ViewProjection for each of"):
        SpaceDrawing(Cuboid((0, 1), (0, 1), (0, 1)), "m", "m/s", views=(ViewProjection("top"),))
    with pytest.raises(ValueError, match=r"zlim: expected \(low, high\) with low < high"):
        Cuboid((0, 1), (0, 1), (1, 0))
    # The belt's line is checked in one place for the plant's conveyor and for the target riding it.
    from mt_widgets.core.chain_plant import Conveyor
    for line in (lambda **k: ConveyorTarget(**k), lambda **k: Conveyor(speed=0.1, **k)):
        with pytest.raises(ValueError, match=r"phase_range: expected \(low, high\) with low < high"):
            line(origin=(0.5, 0, 0.1), direction=(0, 1, 0), phase_range=(0.2, 0.1))
        with pytest.raises(ValueError, match="direction: expected a non-zero vector"):
            line(origin=(0.5, 0, 0.1), direction=(0, 0, 0), phase_range=(0.0, 0.1))
        assert line(origin=(0.5, 0, 0.1), direction=(0, 2, 0), phase_range=(0, 1)).direction == (0.0, 1.0, 0.0)


def test_the_targets_of_the_place_and_reach_skills_are_their_goals():
    assert SKILLS["ur5-reach"].target.point == (0.55, -0.10, 0.10)
    assert SKILLS["ur5-place"].target.point == (0.40, 0.35, 0.12)
    for key in ("ur5-reach", "ur5-place"):
        skill = SKILLS[key]
        trajectory = skill.reproduce(skill.theta, record_every=100)
        assert skill.target.distance(trajectory.final_position) < 2e-3
