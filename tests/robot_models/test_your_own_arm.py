"""docs/guide/your-own-arm.md's worked example runs as written: a user's URDF, its plant, its skills, taught exactly."""

import re
from pathlib import Path

import numpy as np
import pytest

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guide" / "your-own-arm.md"


@pytest.mark.slow   # query states, inverse kinematics and a 10 s reproduction: about 1-4 s
def test_the_worked_example_of_a_users_own_arm_teaches_it_exactly(tmp_path, monkeypatch):
    text = GUIDE.read_text(encoding="utf-8")
    (tmp_path / "my_arm.urdf").write_text(re.search(r"```xml\n(.*?)```", text, re.S).group(1))
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for block in re.findall(r"```python\n(.*?)```", text, re.S):
        exec(block, namespace)
    episode = namespace["episode"]
    assert episode.theta_error < 1e-12
    assert np.linalg.norm(episode.reproduction.final_position - (0.32, -0.08, 0.08)) < 2e-3
    assert namespace["chain"].joint_names == ("turn", "shoulder", "elbow") and namespace["plant"].robot == "my_arm"
    assert sorted(namespace["skills"]) == ["mine-place", "mine-reach"]
    # The one call builds the same skills, checked.
    checked, skills = namespace["checked"], namespace["skills"]
    for key in ("mine-reach", "mine-place"):
        np.testing.assert_array_equal(checked[key].theta, skills[key].theta)
        np.testing.assert_allclose(checked[key].start, skills[key].start, atol=1e-12)
