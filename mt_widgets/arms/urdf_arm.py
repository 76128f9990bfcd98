"""A user's own arm from its URDF and a few numbers: its plant and its production-line skills.

What ``docs/guide/your-own-arm.md`` writes out step by step, in one call, with every number checked
against the arm before a skill is made of it: the home pose inside the joints' ranges, the part,
the fixture and the point above the part within the tool's reach (the inverse kinematics gets
there to 1e-9 m), and a teaching box where query states can be drawn. A study protocol's ``[arm]``
table (``mt_widgets/study/protocol_arm.py``) comes here.

The arm's description comes in as data (``mt_widgets.robot_models.read_urdf`` or ``parse_urdf``):
this module reads no file itself.
"""

from __future__ import annotations

import numpy as np

from mt_widgets.core.chain_plant import ChainPlant, Conveyor
from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.core.skills import Skill, production_line_skills
from mt_widgets.core.validation import as_bool, as_float_array, as_positive
from mt_widgets.core.workspace import Cuboid

#: Of this many states drawn in the teaching box, at least ``MIN_VALID_SHARE`` must be valid query
#: states (reached, clear of the table and the arm, away from singular poses), or the box is refused.
BOX_SAMPLES = 64
MIN_VALID_SHARE = 0.1


def arm_skills(description: dict, name: str, home, teaching_box, part, fixture, *, kinematic: bool = False,
               scene_box=None, conveyor: Conveyor | None = None, lift: float = 0.1, link_radius: float = 0.02,
               max_condition: float = 60.0, min_singular_value: float = 0.05, label: str | None = None,
               query_margin: float = 0.0) -> dict[str, Skill]:
    """An arm's ``<name>-reach`` and ``<name>-place`` skills (and ``<name>-conveyor`` with a conveyor).

    Args:
        description: the arm as a URDF reader gives it (``read_urdf(path, tool=...)``).
        name: the skills' prefix and the plants' robot name (a plain name).
        label: the arm's name in the skills' titles and descriptions ("My arm"); default ``name``.
        home: (n,) the home pose (rad, or m for a prismatic joint): where inverse kinematics starts.
        teaching_box: ((x0, x1), (y0, y1), (z0, z1)) m or a ``Cuboid``: where query states put the tool.
        part, fixture: (3,) m: the reach skill's goal, the place skill's.
        kinematic: position-controlled servos (state q) rather than torque-controlled drives.
        scene_box: what the views frame; default the base, the home pose's chain, the teaching
            box, the part and the fixture, 10 cm around.
        conveyor: a ``Conveyor`` for the conveyor skill, or None.
        lift: how far above the part (m) the place skill starts (as if the part was just picked).
        link_radius: the links' capsule radius (m) for the table and self-collision checks.
        max_condition: the query-state sampler's condition-number threshold.
        min_singular_value: a query state's tool Jacobian must have all singular values above this
            (m/rad), away from stretched and folded poses; 0.05 suits a table-top arm (the SO-101's),
            a UR5-sized one takes 0.15.
        query_margin: how far (rad, or m for a sliding joint) inside each joint's URDF range a query
            state's joints stay: a real arm's controller may allow less than its URDF says (0: the
            URDF's range; the shipped SO-101 keeps 0.1 rad).

    Raises:
        ValueError: naming the argument: a home pose outside a joint's range, a part, fixture or
            start above the part out of the tool's reach, a teaching box the tool cannot be taught
            in, a dynamic arm without inertias.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty name, got {name!r}")
    if label is not None and (not isinstance(label, str) or not label.strip()):
        raise ValueError(f"label: expected a non-empty text or None, got {label!r}")
    kinematic = as_bool("kinematic", kinematic)
    box = teaching_box if isinstance(teaching_box, Cuboid) else _box("teaching_box", teaching_box)
    part = as_float_array("part", part, ndim=1, shape=(3,))
    fixture = as_float_array("fixture", fixture, ndim=1, shape=(3,))
    lift = as_positive("lift", lift)
    source = description.get("source", "the arm") if isinstance(description, dict) else "the arm"
    try:
        chain = SerialChain.from_description(description, dynamics=not kinematic)
    except ValueError as error:
        if kinematic or "<inertial>" not in str(error):
            raise
        # A dynamic arm needs every moving link's mass; an arm of position servos needs none.
        raise ValueError(f"kinematic: false needs the arm's dynamics: {error} (or kinematic=True for an arm of "
                         f"position servos)") from None
    home = as_float_array("home", home, ndim=1)
    if home.shape != (chain.n_joints,):
        raise ValueError(f"home: expected {chain.n_joints} joint values (joints {', '.join(chain.joint_names)}), "
                         f"got {home.shape[0]}")
    if scene_box is None:
        points = np.vstack([chain.frame_origins(home), box.low, box.high, part, fixture, [[0.0, 0.0, 0.0]]])
        scene_box = Cuboid(*zip(points.min(axis=0) - 0.1, points.max(axis=0) + 0.1))
    elif not isinstance(scene_box, Cuboid):
        scene_box = _box("scene_box", scene_box)
    settings = dict(robot=name, kinematic=kinematic, link_radius=link_radius, min_singular_value=min_singular_value,
                    query_margin=query_margin)
    table = ChainPlant(chain, home, box, scene_box, **settings)
    line = None if conveyor is None else ChainPlant(chain, home, box, scene_box, conveyor=conveyor, **settings)
    for what, point in (("part", part), ("fixture", fixture)):
        _reach(table, source, what, point)
    above = _reach(table, source, "lift", part + (0.0, 0.0, lift), f"the point {lift:g} m above the part")
    states = table.sample_states(np.random.default_rng(0), BOX_SAMPLES)
    valid = float(np.mean(table.is_valid_state(states)))
    if valid < MIN_VALID_SHARE:
        raise ValueError(f"teaching_box: expected a box the tool of {source} can be taught in (at least "
                         f"{MIN_VALID_SHARE:.0%} of {BOX_SAMPLES} points in it reached, clear of the table and "
                         f"the arm, away from singular poses), got {valid:.0%} for {box}")
    return production_line_skills(name, label or name, table, part, fixture, above, max_condition, line=line,
                                  conveyor_condition=max_condition)


def _box(name: str, value) -> Cuboid:
    limits = as_float_array(name, value, ndim=2, shape=(3, 2))
    try:
        return Cuboid(*(tuple(row) for row in limits))
    except ValueError as error:  # "xlim: expected (low, high) with low < high, ..."
        raise ValueError(f"{name}: {error}") from None


def _reach(plant: ChainPlant, source: str, name: str, point, what: str | None = None) -> np.ndarray:
    """The state at rest with the tool at ``point``, or a ValueError naming ``name`` and how far it fell short."""
    q, reached = plant.inverse_kinematics(np.asarray(point, dtype=float)[None, :])
    if not reached[0]:
        gap = float(np.linalg.norm(plant.chain.forward_kinematics(q[0]) - point))
        raise ValueError(f"{name}: expected {what or 'a point'} the tool of {source} can reach, got "
                         f"{np.round(point, 6).tolist()} m (the inverse kinematics from the home pose stopped "
                         f"{gap:.3g} m away)")
    return np.concatenate([q[0]] + ([] if plant.kinematic else [np.zeros(plant.n_joints)]))
