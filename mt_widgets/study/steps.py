"""The steps around the task, as protocol data: what a research ethics board expects to see.

A protocol lists them in ``[[before]]`` (between the welcome and the task's instructions) and
``[[after]]`` (between the last phase and the thank-you) tables, in order. Kinds:

- ``text``: a screen of text with a Continue button.
- ``video``: an instruction video, a local file (``file``, relative to the protocol file) or a
  URL (``url``); whether it was watched to the end and how often it was played are logged;
  ``require_watched = true`` keeps Continue off until it has played to the end once.
- ``information``: the information sheet, shown before consent.
- ``consent``: "I agree" or "I do not agree"; declining ends the session (logged, kept out of
  the analysis).
- ``eligibility``: a screener; each item lists the answers that are ``eligible``; any other
  answer ends the session (logged, kept out of the analysis).
- ``demographics``: by default age (a whole number of years) and sex, what the paper reports;
  ``[[before.items]]`` replaces them.

A number item of any asking step may also screen: ``eligible_minimum`` / ``eligible_maximum``
(inside its valid ``minimum`` .. ``maximum``) bound the answers that keep a participant in the
study, so that an age of 17 is a valid answer (not refused as a typo) that ends the session with
the protocol's ``texts.ineligible``, logged as ``screened_out`` like a screener's answer.
- ``questionnaire``: generic items, so that a lab adds NASA-TLX or SUS without code.

Items (``[[before.items]]`` / ``[[after.items]]`` under their step): ``id``, ``kind`` and
``prompt``, ``required`` (default true), and by kind: ``likert`` (``levels``, at least two
labels), ``choice`` (``options``), ``number`` (``minimum``, ``maximum``, ``integer``), ``text``
(``max_length``). ``Item.check(answer)`` validates an answer with a message naming the item.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

from mt_widgets.core.validation import as_bool

#: Where the shipped protocols' media are; a relative video file not found beside the protocol
#: is looked for here (a protocol rebuilt from a study folder's study.json).
SHIPPED_MEDIA = Path(__file__).parent / "protocols"

STEP_KINDS = ("text", "video", "information", "consent", "eligibility", "demographics", "questionnaire")
ITEM_KINDS = ("likert", "choice", "number", "text")
#: Kinds that ask questions (and so need items).
ASKING_KINDS = ("eligibility", "demographics", "questionnaire")

#: What to do with a withdrawn participant's data: keep the log but leave it out of the
#: analysis and the export ("exclude"), or delete the log ("delete"). Either way the
#: withdrawal itself is recorded in the study folder.
WITHDRAWAL_POLICIES = ("exclude", "delete")


@dataclass(frozen=True)
class Item:
    """One question of a step.

    Attributes:
        id: a plain name (the column in exports).
        kind: likert, choice, number or text.
        prompt: the question.
        required: whether an answer is needed to continue.
        levels: a Likert item's labels, low to high (at least two).
        options: a choice item's options.
        minimum, maximum: a number item's bounds (None: open).
        integer: whether a number item takes whole numbers only.
        max_length: a text item's longest answer, characters.
        eligible: in an eligibility step, the answers that keep a participant in the study.
        eligible_minimum, eligible_maximum: a number item's band of answers that keep a
            participant in the study (None: open), inside ``minimum`` .. ``maximum``.
        units: a number item's units (for the data dictionary), e.g. "years".
    """

    id: str
    kind: str
    prompt: str
    required: bool = True
    levels: tuple[str, ...] = ()
    options: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    integer: bool = False
    max_length: int = 2000
    eligible: tuple[str, ...] = ()
    units: str = ""
    eligible_minimum: float | None = None
    eligible_maximum: float | None = None

    @property
    def screens(self) -> bool:
        """Whether some valid answer to this item screens a participant out."""
        return bool(self.eligible) or self.eligible_minimum is not None or self.eligible_maximum is not None

    @property
    def choices(self) -> tuple[str, ...]:
        """The answers a Likert or choice item accepts."""
        return self.levels if self.kind == "likert" else self.options

    def check(self, answer):
        """The answer as stored (str, int or float; None when skipped), or ValueError naming the item."""
        name = f"answers[{self.id!r}]"
        if answer is None or (isinstance(answer, str) and not answer.strip()):
            if self.required:
                raise ValueError(f"{name}: expected an answer to {self.prompt!r}, got none")
            return None
        if self.kind in ("likert", "choice"):
            if answer not in self.choices:
                raise ValueError(f"{name}: expected one of {list(self.choices)}, got {answer!r}")
            return answer
        if self.kind == "number":
            if isinstance(answer, str):
                try:
                    answer = float(answer.strip())
                except ValueError:
                    raise ValueError(f"{name}: expected a number, got {answer!r}") from None
            if isinstance(answer, bool) or not isinstance(answer, (int, float)) or not math.isfinite(answer):
                raise ValueError(f"{name}: expected a finite number, got {answer!r}")
            if self.integer and float(answer) != int(answer):
                raise ValueError(f"{name}: expected a whole number, got {answer!r}")
            if (self.minimum is not None and answer < self.minimum) or \
                    (self.maximum is not None and answer > self.maximum):
                raise ValueError(f"{name}: expected a number in [{self.minimum}, {self.maximum}], got {answer!r}")
            return int(answer) if self.integer else float(answer)
        if not isinstance(answer, str):
            raise ValueError(f"{name}: expected text, got {type(answer).__name__}")
        if len(answer) > self.max_length:
            raise ValueError(f"{name}: expected at most {self.max_length} characters, got {len(answer)}")
        return answer

    def is_eligible(self, answer) -> bool:
        """Whether a (checked) ``answer`` keeps the participant in the study.

        A skipped answer to an item that screens does not: eligibility is not assumed.
        """
        if not self.screens:
            return True
        if self.eligible:
            return answer in self.eligible
        if answer is None:
            return False
        return not ((self.eligible_minimum is not None and answer < self.eligible_minimum) or
                    (self.eligible_maximum is not None and answer > self.eligible_maximum))


#: What the paper reports of its participants: age and sex.
DEFAULT_DEMOGRAPHICS = (
    Item("age", "number", "Your age, in years", minimum=18, maximum=120, integer=True, units="years"),
    Item("sex", "choice", "Your sex", options=("female", "male", "another", "prefer not to say")),
)


@dataclass(frozen=True)
class StudyStep:
    """One step around the task (see the module docstring for the kinds).

    Attributes:
        id: a plain name, unique in the protocol (logged with the step's event).
        kind: one of ``STEP_KINDS``.
        position: "before" or "after" the task.
        title: a heading (may be empty).
        text: what the step says (markdown-free plain text, paragraphs split by blank lines).
        items: the questions of an asking step.
        video: a video step's file path (absolute, resolved from the protocol file) or URL;
            None when a stored protocol's video file is not on this machine.
        video_sha256: the video file's sha256 (part of the protocol's data, so of its hash).
        require_watched: a video step: Continue only once the video has played to the end.
        agree_label, decline_label: a consent step's buttons.
    """

    id: str
    kind: str
    position: str
    title: str = ""
    text: str = ""
    items: tuple[Item, ...] = ()
    video: str | None = None
    require_watched: bool = False
    agree_label: str = "I agree"
    decline_label: str = "I do not agree"
    video_sha256: str | None = None

    @property
    def video_is_url(self) -> bool:
        return bool(self.video) and self.video.split(":", 1)[0] in ("http", "https")

    def item(self, item_id: str) -> Item:
        for item in self.items:
            if item.id == item_id:
                return item
        raise KeyError(f"item_id: expected one of {[i.id for i in self.items]}, got {item_id!r}")

    def check_answers(self, answers) -> dict:
        """Validated answers {item id: value}; unknown ids and missing required answers are refused."""
        if not isinstance(answers, dict):
            raise ValueError(f"answers: expected a dict {{item id: answer}}, got {type(answers).__name__}")
        unknown = sorted(set(answers) - {item.id for item in self.items})
        if unknown:
            raise ValueError(f"answers: expected the items of step {self.id!r} ({[i.id for i in self.items]}), "
                             f"got unknown items {unknown}")
        return {item.id: item.check(answers.get(item.id)) for item in self.items}


def parse_steps(check, raw: dict, position: str, protocol_folder: Path | None, ids: set,
                check_files: bool = True, prefix: tuple = ()) -> tuple[StudyStep, ...]:
    """Validates the ``[[before]]`` or ``[[after]]`` tables of a protocol.

    Args:
        check: the protocol's checker (``fail(path, message)``, ``get``, ``unknown``), which
            names the file, the line and the field of a problem.
        raw: the protocol's top-level table.
        position: "before" or "after".
        protocol_folder: where a video ``file`` is looked for (None: the protocol came as text,
            a relative file cannot be found).
        ids: the step ids taken so far (updated).
        check_files: refuse a video file that does not exist.
        prefix: where ``raw`` is in the protocol (("sessions", 1) for a later session's steps).
    """
    check_files = as_bool("check_files", check_files)
    entries = raw.get(position, [])
    if not isinstance(entries, list) or any(not isinstance(e, dict) for e in entries):
        check.fail(prefix + (position,), f"expected a list of [[{position}]] tables, got {type(entries).__name__}")
    steps = []
    for i, entry in enumerate(entries):
        path = prefix + (position, i)
        step_id = check.get(entry, path + ("id",), "text", name=True)
        if step_id in ids:
            check.fail(path + ("id",), f"expected a unique step id, got {step_id!r} again")
        ids.add(step_id)
        kind = check.get(entry, path + ("kind",), "text", choices=STEP_KINDS)
        allowed = ["id", "kind", "title", "text"]
        if kind == "video":
            allowed += ["file", "url", "require_watched", "sha256"]
        if kind in ASKING_KINDS:
            allowed += ["items"]
        if kind == "consent":
            allowed += ["agree_label", "decline_label"]
        check.unknown(entry, path, tuple(allowed))
        title = check.get(entry, path + ("title",), "text", default="")
        text = check.get(entry, path + ("text",), "text", default="", nonempty=kind in ("information", "consent"))
        if kind in ("information", "consent") and not text:
            check.fail(path + ("text",), f"missing required field (text): a {kind} step shows its text")
        video, watched, sha = None, False, None
        if kind == "video":
            video, watched, sha = _parse_video(check, entry, path, protocol_folder, check_files)
        items: tuple[Item, ...] = ()
        if kind in ASKING_KINDS:
            if "items" in entry or kind != "demographics":
                items = _parse_items(check, entry, path, kind)
            else:
                items = DEFAULT_DEMOGRAPHICS
        labels = {}
        if kind == "consent":
            labels = {key: check.get(entry, path + (key,), "text", nonempty=True, default=default)
                      for key, default in (("agree_label", "I agree"), ("decline_label", "I do not agree"))}
        steps.append(StudyStep(step_id, kind, position, title, text, items, video, watched, **labels,
                               video_sha256=sha))
    return tuple(steps)


def _parse_video(check, entry, path, protocol_folder, check_files):
    has_file, has_url = "file" in entry, "url" in entry
    if has_file == has_url:
        check.fail(path + ("file",), "expected exactly one of file (a video shipped with the study) or url")
    watched = entry.get("require_watched", True)
    if not isinstance(watched, bool):
        check.fail(path + ("require_watched",), f"expected true or false, got {watched!r}")
    stated = check.get(entry, path + ("sha256",), "text", default=None)
    if has_url:
        url = check.get(entry, path + ("url",), "text", nonempty=True)
        if url.split(":", 1)[0] not in ("http", "https"):
            check.fail(path + ("url",), f"expected an http(s) URL, got {url!r}")
        return url, watched, stated
    name = check.get(entry, path + ("file",), "text", nonempty=True)
    file = Path(name).expanduser()
    if not file.is_absolute():
        candidates = ([protocol_folder / file] if protocol_folder is not None else []) + [SHIPPED_MEDIA / file]
        file = next((c for c in candidates if c.is_file()), candidates[0])
    if not file.is_file():
        if check_files:
            check.fail(path + ("file",), f"no video file at {file}")
        return None, watched, stated
    sha = hashlib.sha256(file.read_bytes()).hexdigest()
    if stated is not None and stated != sha:
        check.fail(path + ("sha256",), f"the video file {file} has sha256 {sha}, not the protocol's {stated}")
    return str(file.resolve()), watched, sha


def _parse_items(check, entry, path, kind) -> tuple[Item, ...]:
    raw_items = entry.get("items")
    if not isinstance(raw_items, list) or not raw_items:
        check.fail(path + ("items",), f"expected at least one item: a {kind} step asks questions")
    items, seen = [], set()
    for j, raw in enumerate(raw_items):
        where = path + ("items", j)
        if not isinstance(raw, dict):
            check.fail(where, f"expected a table, got {type(raw).__name__}")
        item_id = check.get(raw, where + ("id",), "text", name=True)
        if item_id in seen:
            check.fail(where + ("id",), f"expected a unique item id in the step, got {item_id!r} again")
        seen.add(item_id)
        item_kind = check.get(raw, where + ("kind",), "text", choices=ITEM_KINDS)
        for key in _BAND_KEYS:
            if key in raw and item_kind != "number":
                check.fail(where + (key,), f"expected {key} only on a number item (an eligible band of "
                                           f"numbers), got it on a {item_kind} item")
        allowed = ["id", "kind", "prompt", "required"] + {
            "likert": ["levels"], "choice": ["options"],
            "number": ["minimum", "maximum", "integer", "units", *_BAND_KEYS], "text": ["max_length"]}[item_kind]
        if kind == "eligibility" and item_kind != "number":
            allowed.append("eligible")
        check.unknown(raw, where, tuple(allowed))
        prompt = check.get(raw, where + ("prompt",), "text", nonempty=True)
        required = raw.get("required", True)
        if not isinstance(required, bool):
            check.fail(where + ("required",), f"expected true or false, got {required!r}")
        fields = {}
        if item_kind in ("likert", "choice"):
            key = "levels" if item_kind == "likert" else "options"
            values = raw.get(key)
            least = 2
            if not isinstance(values, list) or len(values) < least or \
                    not all(isinstance(v, str) and v.strip() for v in values) or len(set(values)) != len(values):
                what = "levels" if item_kind == "likert" else "options"
                check.fail(where + (key,), f"expected at least {least} distinct {what} (labels), got {values!r}")
            fields[key] = tuple(values)
        if item_kind == "number":
            for bound in ("minimum", "maximum"):
                if bound in raw:
                    fields[bound] = check.get(raw, where + (bound,), "number", minimum=-math.inf)
            if fields.get("minimum", -math.inf) > fields.get("maximum", math.inf):
                check.fail(where + ("maximum",), f"expected maximum >= minimum ({fields['minimum']}), "
                                                 f"got {fields['maximum']}")
            integer = raw.get("integer", False)
            if not isinstance(integer, bool):
                check.fail(where + ("integer",), f"expected true or false, got {integer!r}")
            fields["integer"] = integer
            fields["units"] = check.get(raw, where + ("units",), "text", default="")
            fields.update(_parse_band(check, raw, where, fields))
        if item_kind == "text":
            fields["max_length"] = check.get(raw, where + ("max_length",), "count", default=2000, minimum=1,
                                             maximum=100000)
        if kind == "eligibility" and item_kind == "number":
            if fields["eligible_minimum"] is None and fields["eligible_maximum"] is None:
                check.fail(where + ("eligible_minimum",), "expected eligible_minimum and/or eligible_maximum: "
                                                          "a number item of an eligibility step screens by its band")
        elif kind == "eligibility":
            eligible = raw.get("eligible")
            choices = fields.get("levels") or fields.get("options")
            if choices is None:
                check.fail(where + ("kind",), "expected a likert or choice item (its eligible answers "
                                              "listed) or a number item (its eligible band) in an eligibility step")
            if not isinstance(eligible, list) or not eligible or any(e not in choices for e in eligible):
                check.fail(where + ("eligible",), f"expected a non-empty list of answers from {list(choices)}, "
                                                  f"got {eligible!r}")
            fields["eligible"] = tuple(eligible)
        items.append(Item(item_id, item_kind, prompt, required, **fields))
    return tuple(items)


#: A number item's eligible band (see the module docstring).
_BAND_KEYS = ("eligible_minimum", "eligible_maximum")


def _parse_band(check, raw, where, fields) -> dict:
    """A number item's eligible band, refused when it reaches outside the item's valid range:
    an answer the form refuses can never be eligible, so such a band is a typo in the protocol."""
    band = {key: check.get(raw, where + (key,), "number", minimum=-math.inf) if key in raw else None
            for key in _BAND_KEYS}
    low, high = fields.get("minimum", -math.inf), fields.get("maximum", math.inf)
    for key, value in band.items():
        if value is not None and not low <= value <= high:
            check.fail(where + (key,), f"expected a number inside the item's valid range "
                                       f"[{low:g}, {high:g}] (minimum, maximum), got {value:g}")
    if None not in band.values() and band["eligible_minimum"] > band["eligible_maximum"]:
        check.fail(where + ("eligible_maximum",), f"expected eligible_maximum >= eligible_minimum "
                                                  f"({band['eligible_minimum']:g}), got {band['eligible_maximum']:g}")
    return band
