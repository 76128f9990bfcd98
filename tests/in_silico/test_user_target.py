"""A user's own target (a circle, tests/in_silico/circle_skills.py) runs through the in-silico
engine and the figures, which ask it through the ``Target`` methods (``nearest``, ``shape``,
``dimension``) and never by its class."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from mt_widgets.analysis.figures import plot_trajectories
from mt_widgets.in_silico.engine import run_in_silico
from mt_widgets.in_silico.plan import imagined_line_target
from mt_widgets.in_silico.teachers import along_line_offsets, naive_offsets
from mt_widgets.study import load_protocol
from protocols import phase, protocol_toml

SKILLS_FILE = Path(__file__).resolve().parent / "circle_skills.py"

PROTOCOL = protocol_toml("ring-lab", [phase("P1", "sim-point", instructions="Reach the point."),
                                     phase("P2", "sim-ring", 2, "Reach the ring.", guidance=["target"])],
                         skills_module="circle_skills.py")


@pytest.fixture
def protocol(tmp_path):
    shutil.copy(SKILLS_FILE, tmp_path / "circle_skills.py")
    path = tmp_path / "ring.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    return load_protocol(path)


def test_a_synthetic_teacher_aims_at_the_nearest_point_of_a_users_circle(protocol):
    ring = protocol.skills["sim-ring"]
    circle = ring.target
    positions = np.array([[0.8, 2.0], [1.5, 1.2], [0.1, 0.3]])
    onto = positions + naive_offsets(positions, circle)
    np.testing.assert_allclose(np.linalg.norm(onto - circle.centre, axis=1), circle.radius)
    # The circle has extent: the point taught before (P1's) anchors where on it the teacher aims.
    anchor = imagined_line_target(protocol, 1)
    np.testing.assert_allclose(anchor, protocol.skills["sim-point"].target.point)
    along = along_line_offsets(positions, circle, anchor)
    np.testing.assert_allclose(onto + along, np.broadcast_to(circle.nearest(anchor), positions.shape))


def test_an_in_silico_study_of_a_users_circle_runs_and_is_drawn(protocol):
    study = run_in_silico(2, protocol=protocol, seed=3)
    ring = study.episodes[study.episodes.phase == "P2"]
    assert list(ring.skill.unique()) == ["sim-ring"] and len(ring) == 4
    assert np.all(np.isfinite(ring.theta_error))
    participant = str(study.episodes.participant.iloc[0])
    figure = plot_trajectories(study.episodes, [participant], panels=(("P2",),),
                               trajectories=study.reproductions, skills=protocol.skills)
    ax = figure.axes[0]
    drawn = [line for line in ax.lines if line.get_gid() == "target"]
    assert len(drawn) == 1
    points = np.c_[drawn[0].get_xdata(), drawn[0].get_ydata()]
    circle = protocol.skills["sim-ring"].target
    np.testing.assert_allclose(np.linalg.norm(points - circle.centre, axis=1), circle.radius)
    # The zoom of a target with extent centres on where the true skill stops, not on a point.
    zoom = next(child for child in ax.child_axes if child.get_gid() == "zoom")
    truth = protocol.skills["sim-ring"].reproduce(protocol.skills["sim-ring"].theta, record_every=20)
    assert np.allclose([np.mean(zoom.get_xlim()), np.mean(zoom.get_ylim())], truth.positions[-1])
