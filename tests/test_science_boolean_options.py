"""The yes/no options below the widgets (in-silico studies, power, figures, protocols, the skill
registry, the example studies) take only True or False, as tests/widgets/test_boolean_options.py
checks for the widgets: share_states="no" must not share the states, overwrite="no" must not
delete a folder."""

import numpy as np
import pytest

from mt_widgets.analysis.example_studies import write_example_study
from mt_widgets.analysis.figures import plot_trajectories
from mt_widgets.analysis.power import simulated_power
from mt_widgets.core import SKILLS, SkillRegistry
from mt_widgets.in_silico.engine import run_in_silico, run_many_studies, simulate_changes
from mt_widgets.in_silico.progress import Progress
from mt_widgets.in_silico.sessions import run_through_sessions
from mt_widgets.study.protocol import PROTOCOL_FOLDER, load_protocol, parse_protocol
from mt_widgets.study.steps import parse_steps

NOT_BOOLEANS = ["no", "false", "False", 0, 1, np.int64(1)]

PAPER_SIM = PROTOCOL_FOLDER / "paper_sim.toml"


def _registry_replace(value):
    registry = SkillRegistry([SKILLS["sim-point"]])
    registry.add(SKILLS["sim-point"], replace=value)


# Each call either finishes quickly or, when the real work is long, fails later on purpose with
# an error about another argument (n_participants=0, no participants): the option was accepted.
OPTIONS = {
    "reproduce": lambda v: run_in_silico(0, reproduce=v),
    "progress": lambda v: run_in_silico(0, reproduce=False, progress=v),
    "progress ": lambda v: run_many_studies(1, 1, share_states=True, progress=v),
    "progress  ": lambda v: run_through_sessions("unused", 0, progress=v),
    "progress   ": lambda v: simulated_power(2, 2, share_states=True, progress=v),
    "share_states": lambda v: run_many_studies(1, 1, share_states=v),
    "share_states ": lambda v: simulated_power(2, 2, share_states=v),
    "shared": lambda v: simulate_changes(load_protocol("paper-sim"), [], 1, 1, [np.zeros((1, 3, 4))], shared=v),
    "enabled": lambda v: Progress(3, "test", enabled=v),
    "true_skill": lambda v: plot_trajectories([], [], true_skill=v),
    "zoom": lambda v: plot_trajectories([], [], zoom=v),
    "check_files": lambda v: parse_steps(None, {}, "before", None, set(), check_files=v),
    "check_files ": lambda v: parse_protocol(PAPER_SIM.read_text(), str(PAPER_SIM), check_files=v),
    "read_only": lambda v: SkillRegistry(read_only=v),
    "replace": _registry_replace,
    "overwrite": lambda v: write_example_study("/nonexistent-folder/unused", overwrite=v, n_participants=0),
}

OPTIONAL = {"progress", "progress ", "progress  ", "progress   ", "shared"}


def _accepts(call, value, option):
    try:
        call(value)
    except (ValueError, TypeError) as error:
        # Accepted: a later check (of another argument) may stop the call.
        assert not str(error).startswith(f"{option}:"), f"{option}={value!r} refused: {error}"


@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_a_boolean_option_refuses_anything_but_a_bool_and_names_itself(option):
    call, name = OPTIONS[option], option.strip()
    for value in (True, False) + ((None,) if option in OPTIONAL else ()):
        _accepts(call, value, name)
    for value in NOT_BOOLEANS + ([] if option in OPTIONAL else [None]):
        wanted = "True, False or None" if option in OPTIONAL else "True or False"
        with pytest.raises(TypeError, match=rf"^{name}: expected {wanted}, got "):
            call(value)

