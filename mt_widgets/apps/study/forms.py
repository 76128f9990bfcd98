"""The items of an eligibility, demographics or questionnaire step, and its Continue button."""

from __future__ import annotations

import html

from ipywidgets import HTML, RadioButtons, Text, Textarea, VBox

from .controls import Choice
from .texts import answer_problem


class QuestionForm(VBox):
    """Likert and choice items are radio buttons (nothing chosen at first), numbers and short
    answers text fields. ``answers()`` reads them; Continue checks them, says in plain words what
    to fix (``answer_problem``) and, once they are fine, hands them to ``on_submit(answers)``.

    Continue acts once: a double click submits once; after a problem is shown it is offered again.
    """

    def __init__(self, study_step, on_submit):
        self.study_step = study_step
        self.fields = {}
        self._on_submit = on_submit
        rows = []
        for item in study_step.items:
            label = HTML(f"<b>{html.escape(item.prompt)}</b>" + ("" if item.required else " <small>(optional)"
                                                                                           "</small>"))
            if item.kind in ("likert", "choice"):
                field = RadioButtons(options=list(item.choices), value=None, layout={"width": "auto"})
            elif item.kind == "number":
                field = Text(placeholder="a number" + (f" ({item.units})" if item.units else ""),
                             layout={"width": "200px"})
            else:
                field = Textarea(layout={"width": "min(520px, 100%)", "height": "80px"})
            field.add_class(f"mt-item-{item.id}")
            self.fields[item.id] = field
            rows.append(VBox([label, field], layout={"margin": "6px 0"}))
        self.message = HTML()
        self._choice = Choice()
        self.continue_button = self._choice.button("Continue", self._submit)
        super().__init__(rows + [self.message, self.continue_button])

    def answers(self) -> dict:
        found = {}
        for item in self.study_step.items:
            value = self.fields[item.id].value
            found[item.id] = value if value not in ("",) else None
        return found

    def problems(self, answers: dict) -> list[str]:
        """Each answer's problem in plain words (empty when all are fine)."""
        return [problem for item in self.study_step.items
                if (problem := answer_problem(item, answers.get(item.id))) is not None]

    def _submit(self) -> None:
        answers = self.answers()
        problems = self.problems(answers)
        if problems:
            self.say(" ".join(problems))
            self._choice.reopen()
            return
        self.message.value = ""
        self._on_submit(answers)

    def say(self, text: str) -> None:
        self.message.value = f"<div role='alert' style='color:#b00020;max-width:760px'>{html.escape(text)}</div>"
