"""A frozen protocol report for a pre-registration: hash, every parameter, the analysis plan, the power.

``protocol_report(protocol)`` gathers what a pre-registration needs, all read from the
protocol itself: its sha256 (over the normalised data a study folder stores, so a study run
later can be checked against the registered protocol), every parameter as a flat list of
dotted names, the steps around the task (with each video's sha256), the analysis plan (primary
test, sidedness, alpha, the changes compared) and the power analysis the plan implies
(Student's two-sample t-test, noncentral t: the smallest n per group for the planned effect
size and power, and the power it reaches). ``write_protocol_report`` writes it as Markdown and
JSON.
"""

from __future__ import annotations

import json
from pathlib import Path

from mt_widgets.study.protocol import Protocol, load_protocol

from .power import analytic_power, sample_size_per_group
from .summary import TEST_NAMES


def _flatten(value, prefix: str = "") -> list[tuple[str, object]]:
    if isinstance(value, dict):
        out = []
        for key in sorted(value):
            out += _flatten(value[key], f"{prefix}.{key}" if prefix else key)
        return out
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        out = []
        for i, item in enumerate(value):
            out += _flatten(item, f"{prefix}[{i}]")
        return out
    return [(prefix, value)]


def power_analysis(protocol: Protocol) -> dict:
    """The sample size the protocol's analysis plan implies (Student's t, as G*Power computes it).

    A one-sided plan ("less": the target group's change is lower) is the one-tailed test with
    the planned |d|; "two-sided" the two-tailed one.
    """
    plan = protocol.analysis
    alternative = "two-sided" if plan.alternative == "two-sided" else "greater"
    d = abs(plan.effect_size)
    n = sample_size_per_group(d, alpha=plan.alpha, power=plan.power, alternative=alternative)
    return {"test": "Student's two-sample t-test (equal variances), noncentral t", "effect_size_d": d,
            "alpha": plan.alpha, "tails": 2 if alternative == "two-sided" else 1, "power_wanted": plan.power,
            "n_per_group": n, "n_total": n * len(protocol.groups[:2]) if len(protocol.groups) >= 2 else n,
            "power_reached": analytic_power(n, d, plan.alpha, alternative)}


def protocol_report(protocol) -> dict:
    """Everything a pre-registration of ``protocol`` (a ``Protocol``, shipped name or path) states."""
    protocol = protocol if isinstance(protocol, Protocol) else load_protocol(protocol)
    plan = protocol.analysis
    steps = []
    for step in (step for session in protocol.sessions for step in session.steps):
        entry = {"id": step.id, "kind": step.kind, "position": step.position}
        if step.kind == "video":
            entry.update(video=Path(step.video).name if step.video and not step.video_is_url else step.video,
                         sha256=step.video_sha256, require_watched=step.require_watched)
        if step.items:
            entry["items"] = [{"id": i.id, "kind": i.kind, "prompt": i.prompt, "choices": list(i.choices),
                               "eligible": list(i.eligible)} for i in step.items]
        steps.append(entry)
    return {
        "name": protocol.name, "title": protocol.title, "hash": protocol.hash,
        "parameters": [{"name": name, "value": value} for name, value in _flatten(protocol.data)],
        "steps": steps,
        "phases": [{"id": p.id, "skill": p.skill, "episodes": p.episodes, "demonstrations": p.demonstrations,
                    "guidance": list(p.guidance), "session": p.session} for p in protocol.all_phases],
        "sessions": [{"id": s.id, "phases": [p.id for p in s.phases],
                      "window": None if s.window is None else s.window.describe(),
                      "too_early": None if s.window is None else s.window.too_early,
                      "too_late": None if s.window is None else s.window.too_late} for s in protocol.sessions],
        "groups": list(protocol.groups),
        "guidance_modality": protocol.guidance_modality, "withdrawal": protocol.withdrawal,
        "analysis_plan": {**plan.as_dict(), "primary_test_name": TEST_NAMES[plan.test],
                          "also_reported": [TEST_NAMES[t] for t in TEST_NAMES if t != plan.test]},
        "power_analysis": power_analysis(protocol),
    }


def report_markdown(report: dict) -> str:
    """The report as Markdown, for a pre-registration form or an appendix."""
    plan, power = report["analysis_plan"], report["power_analysis"]
    lines = [f"# Protocol report: {report['title']}", "", f"- Protocol: `{report['name']}`",
             f"- Hash: `{report['hash']}`", f"- Guidance: {report['guidance_modality']}; withdrawal: "
             f"{report['withdrawal']}", "", "## Phases", "", "| phase | skill | episodes | demonstrations | guided |",
             "|---|---|---|---|---|"]
    lines += [f"| {p['id']} | {p['skill']} | {p['episodes']} | {p['demonstrations']} | "
              f"{', '.join(p['guidance']) or '-'} |" for p in report["phases"]]
    if len(report["sessions"]) > 1:
        lines += ["", "## Sessions", ""]
        for session in report["sessions"]:
            when = (f"{session['window']}; too early: {session['too_early']}, too late: {session['too_late']}"
                    if session["window"] else "first session")
            lines.append(f"- `{session['id']}`: phases {', '.join(session['phases'])} ({when})")
    lines += ["", "## Steps around the task", ""]
    for step in report["steps"]:
        extra = f" (video {step['video']}, sha256 {step['sha256']})" if step["kind"] == "video" else ""
        items = f": items {', '.join(i['id'] for i in step.get('items', []))}" if step.get("items") else ""
        lines.append(f"- {step['position']}: `{step['id']}` ({step['kind']}){extra}{items}")
    lines += ["", "## Analysis plan", "",
              f"- Primary test: {plan['primary_test_name']}, {plan['alternative']} ({report['groups'][0]} minus "
              f"{report['groups'][1] if len(report['groups']) > 1 else 'the other group'}), "
              f"alpha = {plan['alpha']}; also reported: {', '.join(plan['also_reported'])}",
              "- Changes (later minus earlier teaching error): " + "; ".join(
                  f"{c['label']} ({c['meaning']})" for c in plan["changes"]),
              "", "## Power analysis", "",
              f"- {power['test']}: d = {power['effect_size_d']}, alpha = {power['alpha']}, {power['tails']}-tailed, "
              f"power {power['power_wanted']}: **{power['n_per_group']} per group** ({power['n_total']} in all), "
              f"power reached {power['power_reached']:.4f}", "", "## Every parameter", "", "| parameter | value |",
              "|---|---|"]
    for entry in report["parameters"]:
        value = json.dumps(entry["value"], ensure_ascii=False)
        lines.append(f"| `{entry['name']}` | {value if len(value) < 120 else value[:117] + '...'} |")
    return "\n".join(lines) + "\n"


def write_protocol_report(protocol, folder) -> tuple[Path, Path]:
    """Writes ``protocol_report.md`` and ``protocol_report.json`` into ``folder``; returns both paths."""
    report = protocol_report(protocol)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    markdown, data = folder / "protocol_report.md", folder / "protocol_report.json"
    markdown.write_text(report_markdown(report), encoding="utf-8")
    data.write_text(json.dumps(report, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return markdown, data
