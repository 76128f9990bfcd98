"""How plants and targets are drawn (as data), targets as objects, and skill registries."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.core import Box, LineTarget, PlantDrawing, PointTarget, Skill, SkillRegistry, Target, TargetShape
from mt_widgets.core.drawing import clip_line, framing_box


def test_the_arm_sketches_its_links_through_its_joints():
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=1)
    sketch = skill.sketch(states)
    np.testing.assert_allclose(sketch.chain, skill.plant.arm.joint_positions(states[:, :2]))
    np.testing.assert_allclose(sketch.end_effector, skill.end_effector(states)[0])
    np.testing.assert_allclose(sketch.velocity, skill.end_effector(states)[1])
    assert sketch.joints.shape == (5, 1, 2), "one joint (the elbow) between base and hand"
    drawing = skill.drawing()
    assert (drawing.links, drawing.marker, drawing.base, drawing.units) == ("rigid", "hand", (0.0, 0.0), "m")
    assert drawing.action_length == 0.35


def test_the_uarm_sketches_a_reach_line_and_outlines_its_sector():
    skill = SKILLS["uarm-point"]
    sketch = skill.sketch(np.array([[20.0, 5.0], [15.0, -3.0]]))
    np.testing.assert_allclose(sketch.chain, [[[0, 0], [20, 5]], [[0, 0], [15, -3]]])
    np.testing.assert_allclose(sketch.velocity, 0.0)
    drawing = skill.drawing()
    assert (drawing.links, drawing.marker, drawing.units, drawing.action_length) == ("reach", "dot", "cm", 2.0)
    (outline,) = drawing.outline
    radius = np.hypot(*outline.T)
    sector = skill.plant.workspace
    assert np.all((np.abs(radius - sector.r_min) < 1e-9) | (np.abs(radius - sector.r_max) < 1e-9))
    np.testing.assert_allclose(outline[0], outline[-1]), "a closed outline"


def test_a_plant_drawing_refuses_what_no_view_can_draw():
    with pytest.raises(ValueError, match="links: expected one of"):
        PlantDrawing(Box((0, 1), (0, 1)), "m", "N", links="springs")
    with pytest.raises(ValueError, match="action_length"):
        PlantDrawing(Box((0, 1), (0, 1)), "m", "N", action_length=-1.0)
    with pytest.raises(TypeError, match="view: expected a Box"):
        PlantDrawing(((0, 1), (0, 1)), "m", "N")


def test_framing_and_clipping():
    box = framing_box([[0.0, 0.0], [2.0, 1.0]], pad=0.25)
    assert box.xlim == (-0.5, 2.5) and box.ylim == pytest.approx((-1.0, 2.0))
    segment = clip_line((0.5, 0.0), (1.0, 1.0), Box((0, 2), (0, 1)))
    np.testing.assert_allclose(segment, [[0.5, 0.0], [1.5, 1.0]])
    assert clip_line((5.0, 5.0), (1.0, 0.0), Box((0, 2), (0, 1))) is None


def test_targets_are_objects_that_measure_draw_and_name_themselves():
    point = PointTarget((0.8, 1.2))
    line = LineTarget((0.8, 0.0), (0.0, 2.0))
    slanted = LineTarget((0.0, 0.0), (2.0, 1.0))
    assert isinstance(point, Target) and isinstance(line, Target)
    assert line.direction == (0.0, 1.0) and line.point == (0.8, 0.0), "constructors and fields as before"
    positions = np.array([[0.8, 0.2], [1.8, 1.2]])
    np.testing.assert_allclose(point.distance(positions), [1.0, 1.0])
    np.testing.assert_allclose(line.distance(positions), [0.0, 1.0])
    np.testing.assert_allclose(line.nearest(positions), [[0.8, 0.2], [0.8, 1.2]])
    np.testing.assert_allclose(slanted.nearest([5.0, 0.0]), [4.0, 2.0])
    assert (point.dimension, line.dimension) == (0, 1)
    view = Box((-2.2, 2.2), (-2.2, 2.2))
    assert point.shape(view).is_point and np.allclose(point.shape(view).points, [[0.8, 1.2]])
    drawn = line.shape(view)
    np.testing.assert_allclose(drawn.points, [[0.8, -2.2], [0.8, 2.2]])
    np.testing.assert_allclose(drawn.label_at, [0.8, 0.0])
    assert point.describe("orange", "goal") == "the orange point marked goal"
    assert line.describe("red") == "the red vertical line"
    assert slanted.describe() == "the line"
    assert LineTarget((0, 1), (3, 0)).noun == "horizontal line"
    with pytest.raises(ValueError, match="direction: expected a non-zero vector"):
        LineTarget((0, 0), (0, 0))


def test_a_skill_refuses_a_target_that_is_not_a_target():
    base = SKILLS["sim-point"]
    with pytest.raises(TypeError, match="target: expected a Target"):
        Skill("x", "x", base.plant, base.feature_map, base.theta, base.start, target=(0.8, 1.2))


class Ring(Target):
    """A user's own target: the circle of radius 0.5 around the origin."""

    noun = "circle"
    dimension = 1

    def nearest(self, positions):
        positions = np.asarray(positions, dtype=float)
        return 0.5 * positions / np.linalg.norm(positions, axis=-1, keepdims=True)

    def shape(self, view):
        angles = np.linspace(0, 2 * np.pi, 65)
        return TargetShape(0.5 * np.c_[np.cos(angles), np.sin(angles)], np.array([0.5, 0.0]))


def test_a_users_target_subclass_works_through_the_same_methods():
    ring = Ring()
    np.testing.assert_allclose(ring.distance([[2.0, 0.0], [0.0, 0.25]]), [1.5, 0.25])
    base = SKILLS["sim-point"]
    skill = Skill("ring", "Circle", base.plant, base.feature_map, base.theta, base.start, target=ring)
    assert len(skill.target_shape().points) == 65 and ring.describe("blue", "goal") == "the blue circle marked goal"


def test_skills_live_in_registries_their_users_own():
    # The paper's four, the UR5's production line (issue 31), the Panda's and the SO-101's (issue 41).
    assert set(SKILLS) == {"sim-point", "sim-line", "uarm-point", "uarm-line", "ur5-reach", "ur5-place",
                           "ur5-conveyor", "panda-reach", "panda-place", "panda-conveyor", "so101-reach", "so101-place"}
    with pytest.raises(KeyError, match=r"^skill: expected one of the known skills \(panda-conveyor, .*sim-line"):
        SKILLS["nope"]
    base = SKILLS["sim-point"]
    mine = Skill("sim-stiff", "Stiff", base.plant, base.feature_map, 3 * base.theta, base.start,
                 target=PointTarget((0.8, 1.2)))
    with pytest.raises(TypeError, match="read-only"):
        SKILLS["sim-stiff"] = mine
    with pytest.raises(TypeError, match="read-only"):
        SKILLS.add(mine)
    registry = SkillRegistry(SKILLS.values())
    assert registry.add(mine) is mine and registry["sim-stiff"] is mine and len(registry) == len(SKILLS) + 1
    assert "sim-stiff" not in SKILLS, "the paper's registry is untouched"
    other = Skill("sim-stiff", "Another", base.plant, base.feature_map, base.theta, base.start)
    with pytest.raises(ValueError, match="already taken"):
        registry.add(other)
    registry.add(other, replace=True)
    assert registry["sim-stiff"] is other
    del registry["sim-stiff"]
    assert "sim-stiff" not in registry
    with pytest.raises(TypeError, match="skill: expected a Skill"):
        registry.add("sim-point")
    with pytest.raises(TypeError, match="read_only: expected True or False"):
        SkillRegistry(read_only="yes")
