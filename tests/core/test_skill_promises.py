"""A registry's promised skills: built on first use, once, under the keys promised (``SkillRegistry.defer``)."""

import subprocess
import sys
import threading

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.arms import SHIPPED_ARMS
from mt_widgets.core import Skill, SkillRegistry

SIM = SKILLS["sim-point"]


def _copy(key: str) -> Skill:
    return Skill(key, f"A copy as {key}", SIM.plant, SIM.feature_map, SIM.theta, SIM.start, SIM.target)


class CountingBuild:
    def __init__(self, *keys):
        self.keys, self.calls = keys, 0

    def __call__(self):
        self.calls += 1
        return [_copy(key) for key in self.keys]


def test_a_promise_is_listed_without_being_built_and_built_once_on_first_use():
    build = CountingBuild("a", "b")
    registry = SkillRegistry([SIM])
    registry.defer(("a", "b"), build)
    assert list(registry) == ["sim-point", "a", "b"] and len(registry) == 3
    assert "a" in registry and "c" not in registry and [] not in registry
    assert build.calls == 0, "listing and membership build nothing"
    first = registry["b"]
    assert build.calls == 1 and first.key == "b" and registry["a"].key == "a"
    assert registry["b"] is first and build.calls == 1, "built once: the skills keep their identity"
    np.testing.assert_array_equal(first.theta, SIM.theta)


def test_two_threads_asking_at_once_get_one_build():
    build = CountingBuild("a")
    registry = SkillRegistry()
    registry.defer(["a"], build)
    found = []
    threads = [threading.Thread(target=lambda: found.append(registry["a"])) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert build.calls == 1 and all(skill is found[0] for skill in found)


def test_a_read_only_registry_takes_promises_of_new_keys_only():
    registry = SkillRegistry([SIM], read_only=True)
    registry.defer(("a",), CountingBuild("a"))
    assert registry["a"].key == "a"
    with pytest.raises(TypeError, match="read-only"):
        registry.add(_copy("c"))
    with pytest.raises(ValueError, match=r"keys: expected keys not yet taken, got \['sim-point'\]"):
        registry.defer(("sim-point",), CountingBuild("sim-point"))
    with pytest.raises(ValueError, match="keys: expected keys not yet taken"):
        registry.defer(("a",), CountingBuild("a"))


def test_a_promise_that_builds_other_keys_or_no_skills_is_refused_when_it_runs():
    registry = SkillRegistry()
    registry.defer(("a", "b"), CountingBuild("a", "x"))
    with pytest.raises(ValueError, match=r"build: expected skills under the promised keys \['a', 'b'\], "
                                         r"got \['a', 'x'\]"):
        registry["a"]
    registry.defer(("c",), lambda: ["not a skill"])
    with pytest.raises(TypeError, match="build: expected Skills, got str"):
        registry["c"]


@pytest.mark.parametrize("keys, build, error, match", [
    ("ab", CountingBuild("ab"), TypeError, "keys: expected skill keys"),
    ((), CountingBuild(), ValueError, "keys: expected distinct non-empty"),
    (("a", "a"), CountingBuild("a"), ValueError, "keys: expected distinct non-empty"),
    (("a", 3), CountingBuild("a"), ValueError, "keys: expected distinct non-empty"),
    (("a",), "build", TypeError, "build: expected a function"),
])
def test_a_promise_is_checked_when_made(keys, build, error, match):
    with pytest.raises(error, match=match):
        SkillRegistry().defer(keys, build)


def test_a_promised_key_replaced_before_its_build_keeps_its_replacement():
    registry = SkillRegistry()
    registry.defer(("a", "b"), CountingBuild("a", "b"))
    mine = registry.add(_copy("a"), replace=True)
    assert registry["b"].key == "b" and registry["a"] is mine


def test_importing_the_package_builds_no_arm_and_skills_lists_every_shipped_one():
    # A fresh process: this one's tests may have built the arms already.
    script = ("from mt_widgets.core.skills import SKILLS, Skill\n"
              "print(','.join(k for k, v in SKILLS._skills.items() if not isinstance(v, Skill)))\n"
              "print(','.join(SKILLS))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=120)
    unbuilt, listed = done.stdout.split()
    arms = [key for arm in SHIPPED_ARMS for key in arm.keys]
    assert unbuilt.split(",") == arms and len(arms) == 8
    assert listed.split(",") == ["sim-point", "sim-line", "uarm-point", "uarm-line", *arms]


@pytest.mark.parametrize("arm", SHIPPED_ARMS, ids=lambda arm: arm.robot)
def test_a_shipped_arms_listed_titles_are_its_skills_own(arm):
    assert [(SKILLS[key].title, key) for key in arm.keys] == list(arm.skills)
    assert {SKILLS[key].robot for key in arm.keys} == {arm.robot}
