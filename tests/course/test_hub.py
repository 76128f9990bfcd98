"""A real class on JupyterHub, end to end on loopback, as root, tested as an outsider and as a classmate.

One hub for the module, with a roster of an instructor and thirty-odd students, all system users
``mtt-...`` made by the hub and removed at the end with their cgroups:

- only the roster's people come in, each with their own password; the instructor's cannot be
  guessed or claimed; repeated wrong passwords lock a login; the instructor's command adds,
  removes and resets mid-term;
- a student's kernel is their own system user: it cannot read a classmate's home or progress
  file, nor the instructor's course folder, nor write into the installation;
- a runaway allocation in one student's kernel is stopped by their memory limit while
  classmates' episodes finish;
- thirty students log in within the same moment, every server and kernel starts and every
  episode completes, with no retry; two of them draw in Chromium, and the instructor's class
  view shows them all;
- nbgrader's exchange works through the hub, and a student cannot list others' submissions;
- the thirty, each mid-episode, keep their servers and kernels through a hub stopped, a hub killed
  and a proxy killed, and nothing of theirs is left after the class ends (issue 46);
- on a small hub of its own: a full class server and a full disk under the hub's database are
  refused in words, the database whole (issue 46).

Slow (a few minutes on two cores): a class is thirty Jupyter servers.
"""

from __future__ import annotations

import grp
import json
import os
import pwd
import shutil
import signal
import sqlite3
import statistics
import time
import warnings
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import nbformat
import psutil
import pytest
import requests

from browser_support import REPO, artifact_path, local_page
from disk_support import fill_filesystem
from mt_widgets.classroom import read_class, summarise
from tests.browser.helpers import drag, ee_pixel, reference_episode

from .course_support import source_notebook
from .hub_support import (
    EPISODE_CODE,
    HUB_ACCOUNT,
    TEST_INSTRUCTORS,
    TEST_PREFIX,
    ClassHub,
    LoginRefused,
    other_test_hub_running,
    remove_leftovers_unless_busy,
    warm_numba_template,
)

pytestmark = [pytest.mark.slow, pytest.mark.browser,
              pytest.mark.skipif(os.geteuid() != 0, reason="the class hub makes system users: run as root")]

INSTRUCTOR = "mtt-teacher"
INSTRUCTOR_PASSWORD = "the instructor's own passphrase"
STUDENTS = [f"mtt-s{number:02d}" for number in range(30)]
GUESSED, RUNAWAY, LEAVER = "mtt-guessed", "mtt-runaway", "mtt-leaver"
LATE = "mtt-late"  # added mid-term with the instructor's command
DRAWERS = STUDENTS[:2]
ASSIGNMENT = "a1_ridge_learner"


def password_of(login: str) -> str:
    return f"{login}'s first password"


DRAW_PAGE = """
from ipywidgets import Label
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.classroom import ProgressRecorder

episode = EpisodeWidget("sim-point", seed=0, guidance=True, duration=2.0, css_width="360px")
ProgressRecorder().attach(episode, "hub-draw")
confirmed = Label("confirmed 0")
episode.observe(lambda change: setattr(confirmed, "value", f"confirmed {len(change['new'])}"), names="demonstrations")
display(confirmed, episode)
"""

#: Run in one student's kernel: what it can reach of others' work and of the installation.
PROBE_CODE = """
import json, os, pathlib, sys
from mt_widgets.classroom import ProgressRecorder, pseudonym, read_class_meta

def attempt(action):
    try:
        action()
        return "allowed"
    except PermissionError:
        return "denied"

folder = pathlib.Path(os.environ["MT_WIDGETS_CLASS_FOLDER"])
salt = read_class_meta(folder)["salt"]
classmate_progress = folder / (pseudonym({classmate!r}, salt) + ".jsonl")
ProgressRecorder().record("lesson", lesson="probe")
own = folder / (pseudonym({me!r}, salt) + ".jsonl")
installed = pathlib.Path({package!r})
site = pathlib.Path(json.__file__).parent
result = {{
    "uid": os.getuid(), "euid": os.geteuid(), "groups": os.getgroups(),
    "read_classmate_home": attempt(lambda: os.listdir({classmate_home!r})),
    "read_classmate_file": attempt(lambda: open({classmate_file!r}).read()),
    "list_class_folder": attempt(lambda: os.listdir(folder)),
    "read_classmate_progress": attempt(lambda: open(classmate_progress).read()),
    "append_classmate_progress": attempt(lambda: open(classmate_progress, "a").write("{{}}\\n")),
    "take_classmate_lock": attempt(lambda: open(folder / ".locks" / (classmate_progress.stem + ".lock"), "a")),
    "own_progress_lines": len(own.read_text().splitlines()),
    "list_course": attempt(lambda: os.listdir({course!r})),
    "read_course_source": attempt(lambda: open({course_file!r}).read()),
    "write_package": attempt(lambda: open(installed / "planted.py", "w").write("x = 1")),
    "write_stdlib": attempt(lambda: open(site / "planted.py", "w").write("x = 1")),
    "become_root": attempt(lambda: os.setuid(0)),
    "kernel_command": open("/proc/self/cmdline").read().split("\\0"),
    "debugger_loaded": "debugpy" in sys.modules and sys.modules["debugpy"] is not None,
    # Without a debugger the kernel skips listing every module's file (mt_widgets/kernels/template.py);
    # ipykernel's own module sees the real sys again once the kernel is made.
    "kernel_module_list": len(get_ipython().kernel._kernel_modules),
    "ipkernel_sys_is_sys": __import__("ipykernel.ipkernel").ipkernel.sys is sys,
}}
print(json.dumps(result))
"""


def _page(folder: Path, name: str, code: str, owner: str) -> None:
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(notebook, folder / name)
    user = pwd.getpwnam(owner)
    os.chown(folder / name, user.pw_uid, user.pw_gid)


def _files(folder: Path) -> dict[str, float]:
    return {str(p.relative_to(folder)): p.stat().st_mtime for p in folder.rglob("*")}


def _test_accounts(logins=None) -> list[str]:
    """The accounts with the test prefix (of ``logins`` only, when given)."""
    return sorted(user.pw_name for user in pwd.getpwall()
                  if user.pw_name.startswith(TEST_PREFIX) and (logins is None or user.pw_name in logins))


def _stray_accounts() -> list[str]:
    """Accounts with the test prefix that no hub made (a test hub's own are another run's, not strays)."""
    return sorted(user.pw_name for user in pwd.getpwall()
                  if user.pw_name.startswith(TEST_PREFIX) and user.pw_gecos != HUB_ACCOUNT)


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    template = tmp_path_factory.getbasetemp() / "numba-template"
    warm_numba_template(template)
    draw_start = ee_pixel(reference_episode("episode_sim.ipynb"), 0)
    installed_before = _files(REPO / "mt_widgets")
    # A run killed from outside (a CI timeout) cannot clean up; its accounts would make the roster's
    # logins clash with existing users, so they go first, and the run says so.
    left = remove_leftovers_unless_busy()
    if left:
        warnings.warn(f"removed {len(left)} test accounts an earlier, killed run left: {left[:3]}...", stacklevel=2)
    assert _stray_accounts() == [], "test accounts that are not the hub's own use the test prefix"
    roster = [*STUDENTS, GUESSED, RUNAWAY, LEAVER, INSTRUCTOR, LATE]
    assert _test_accounts(roster) == [], "this class's logins exist already (another run of this module?)"
    class_hub = ClassHub([*STUDENTS, GUESSED, RUNAWAY, LEAVER], [INSTRUCTOR], numba_template=template,
                         mem_limit="800M")
    class_hub.installed_before, class_hub.draw_start = installed_before, draw_start
    try:
        class_hub.set_password(INSTRUCTOR, INSTRUCTOR_PASSWORD)
        yield class_hub
    finally:
        class_hub.stop()
        # The hub's log (hub, proxy, every student's server) outlives the temporary folder.
        shutil.copy(class_hub.kept_log, artifact_path("test_hub", "jupyterhub").replace(".png", ".log"))
        class_hub.kept_log.unlink()
    # Nothing of the class is left on the machine (the instructors' group is shared with any other
    # test hub still running, which removes it when it stops).
    assert _test_accounts(roster) == []
    if not other_test_hub_running():
        assert TEST_INSTRUCTORS not in {group.gr_name for group in grp.getgrall()}
    assert not list(Path("/sys/fs/cgroup/memory").rglob(class_hub.cgroup))
    assert not class_hub.root.exists()


#: A student mid-episode: one demonstration given, the episode's state in their kernel.
MID_EPISODE = """
from mt_widgets.widgets import EpisodeWidget
episode = EpisodeWidget("sim-point", seed=3, guidance=False)
episode.demonstrate(episode.optimal[0] + 0.1)
episode_mark = {name!r}
"""
#: Their next demonstration, in the same kernel (a NameError if the kernel was lost).
NEXT_DEMONSTRATION = "episode.demonstrate(episode.optimal[1] + 0.1)\nprint(episode_mark)"


def _post_login(hub, name: str, password: str) -> requests.Response:
    """The login form sent as a browser does, following every redirect; the last page."""
    browser = requests.Session()
    browser.get(f"{hub.url}/hub/login", timeout=60).raise_for_status()
    return browser.post(f"{hub.url}/hub/login", timeout=120, data={
        "username": name, "password": password, "_xsrf": browser.cookies.get("_xsrf") or ""})


def _integrity(database: Path) -> list:
    """SQLite's own check of every page and index of ``database`` (read only)."""
    with sqlite3.connect(f"file:{database}?mode=ro", uri=True) as connection:
        return connection.execute("PRAGMA integrity_check").fetchall()


@pytest.mark.timeout(600)
def test_a_full_class_server_and_a_full_disk_under_the_hubs_database_are_refused_in_words():
    """Issue 46, a small hub of its own (two students, a late one and a newcomer), before the module's
    class hub starts; about 40 s.

    - The machine full (``MT_HUB_SERVER_LIMIT``): the third student gets the page saying so.
    - The disk under the hub's state (its SQLite database, the password hashes: a real 4 MiB
      tmpfs) fills up while a student is mid-episode: a newcomer's first login and a student's
      login are refused with a page in words (HTTP 500, not a bare error) and a log line naming
      the folder; the running student's kernel goes on; the database passes SQLite's integrity
      check. When space returns the newcomer comes in without a restart, and the hub stopped and
      started again has every user it had, the database still whole."""
    students = ["mtt-rs0", "mtt-rs1"]
    late, newcomer = "mtt-rs2", "mtt-rs3"
    try:
        left = remove_leftovers_unless_busy()
    except RuntimeError:  # another test hub runs on this machine: its accounts are not leftovers
        left = []
    if left:
        warnings.warn(f"removed {len(left)} test accounts an earlier, killed run left", stacklevel=2)
    small = ClassHub([*students, late, newcomer], spawn_limit=10, state_size="4m",
                     env={"MT_HUB_SERVER_LIMIT": str(len(students)), "MT_HUB_CULL_IDLE_SECONDS": "0"})
    try:
        small.login(students[0], password_of(students[0]))
        small.create_users(students)
        small.spawn_class(students)
        # The machine is full (MT_HUB_SERVER_LIMIT): the next student is told so in a page, not a spinner.
        refused = small.login(late, password_of(late)).get(f"{small.url}/hub/spawn", timeout=60)
        assert refused.status_code == 429 and "The class server is full" in refused.text, refused.text[-2000:]
        assert not small.processes(late)
        begun = small.run_in_kernel(students[0], MID_EPISODE.format(name=students[0]))
        assert begun["error"] is None, begun
        users_before = {user["name"] for user in small.api("GET", "/users")}

        filler = fill_filesystem(small.state)
        database = small.state / "jupyterhub.sqlite"
        # A newcomer's first login (their password hash and their user to write) and a student's
        # login (a token for their server to record): each refused with the page in words.
        for name in (newcomer, students[0]):
            page = _post_login(small, name, password_of(name))
            assert page.status_code == 500 and "The class server's disk is full" in page.text, (name, page.text[-3000:])
            assert 'data-reason="disk-full"' in page.text and "Nothing of yours is lost" in page.text
        assert "Disk full: the hub's state folder " + str(small.state) in small.tail(200_000)
        # A student already working goes on: the proxy routes to their server, the hub is not asked.
        going_on = small.run_in_kernel(students[0], NEXT_DEMONSTRATION, timeout=30, kernel_id=begun["kernel_id"])
        assert going_on == {**going_on, "stdout": f"{students[0]}\n", "error": None, "died": False}, going_on
        assert _integrity(database) == [("ok",)]

        # Space returns: the newcomer comes in, with no restart.
        filler.unlink()
        small.login(newcomer, password_of(newcomer))  # raises unless the hub answers with its cookie
        # The hub stopped and started again has every user it had, the newcomer too.
        small.restart(signal.SIGTERM)
        assert {user["name"] for user in small.api("GET", "/users")} == users_before | {newcomer}
        assert _integrity(database) == [("ok",)]
        going_on = small.run_in_kernel(students[0], NEXT_DEMONSTRATION, timeout=30, kernel_id=begun["kernel_id"])
        assert going_on["error"] is None and not going_on["died"], going_on
    finally:
        small.stop()


@pytest.mark.timeout(300)
def test_only_the_roster_comes_in_each_with_their_own_password(hub):
    # The instructor: a made-up password is refused; theirs (set with class_admin.py) is not.
    with pytest.raises(LoginRefused):
        hub.login(INSTRUCTOR, "instructor")
    with pytest.raises(LoginRefused):
        hub.login(INSTRUCTOR, "a made-up but long password")
    hub.login(INSTRUCTOR, INSTRUCTOR_PASSWORD)
    # Not on the roster: refused, whatever the password; system accounts too.
    for stranger in ("mtt-stranger", "root", "nobody"):
        with pytest.raises(LoginRefused):
            hub.login(stranger, "a long enough password")
    # A student's first login sets their password (a short one is refused); then only that one works.
    with pytest.raises(LoginRefused):
        hub.login(GUESSED, "short")
    hub.login(GUESSED, password_of(GUESSED))
    with pytest.raises(LoginRefused):
        hub.login(GUESSED, "someone else's claim")
    hub.login(GUESSED, password_of(GUESSED))
    # Five wrong passwords in a row lock the login: then even the right one is refused.
    for attempt in range(5):
        with pytest.raises(LoginRefused):
            hub.login(GUESSED, f"guess number {attempt}")
    with pytest.raises(LoginRefused):
        hub.login(GUESSED, password_of(GUESSED))
    assert "locked" in hub.tail(200_000)
    passwords = json.loads((hub.root / "state" / "passwords.json").read_text())
    assert password_of(GUESSED) not in json.dumps(passwords) and passwords[GUESSED].startswith("scrypt$")
    assert oct((hub.root / "state" / "passwords.json").stat().st_mode & 0o777) == "0o600"

    # Mid-term, with the instructor's command and no restart: a new student comes in, one who left does not.
    with pytest.raises(LoginRefused):
        hub.login(LATE, password_of(LATE))
    added = hub.class_admin("add", LATE, "--name", "Late Comer")
    assert added.returncode == 0, added.stderr
    hub.login(LATE, password_of(LATE))
    assert pwd.getpwnam(LATE).pw_uid != 0
    hub.students.append(LATE)  # so that stop() removes the account
    hub.login(LEAVER, password_of(LEAVER))
    removed = hub.class_admin("remove", LEAVER)
    assert removed.returncode == 0, removed.stderr
    with pytest.raises(LoginRefused):
        hub.login(LEAVER, password_of(LEAVER))
    # A forgotten password: reset, then the student sets a new one at the next login.
    reset = hub.class_admin("reset-password", LATE)
    assert reset.returncode == 0, reset.stderr
    hub.login(LATE, "a brand new password")
    with pytest.raises(LoginRefused):
        hub.login(LATE, password_of(LATE))
    # An admin's password is never reset to first-login claiming.
    assert hub.class_admin("reset-password", INSTRUCTOR).returncode == 1
    # A bad roster is refused with its line and reason, and the roster file stays as it was.
    before = hub.roster.read_text()
    bad = hub.class_admin("add", "Bad Login")
    assert bad.returncode == 1 and "unsafe login 'Bad Login'" in bad.stderr
    assert hub.roster.read_text() == before


@pytest.mark.timeout(300)
def test_a_students_kernel_is_their_own_user_and_reaches_no_one_elses_work(hub):
    me, classmate = STUDENTS[2], STUDENTS[3]
    for name in (me, classmate):
        hub.ensure_running(name)
    # The classmate saves a notebook; the instructor's course holds a solution.
    hub.server_api(classmate, "PUT", "/api/contents/mine.ipynb",
                   json={"type": "notebook", "content": nbformat.v4.new_notebook()})
    (hub.course / "source").mkdir(exist_ok=True)
    (hub.course / "source" / "solution.py").write_text("answer = 42\n")
    code = PROBE_CODE.format(me=me, classmate=classmate, classmate_home=str(hub.homes / classmate),
                             classmate_file=str(hub.homes / classmate / "mine.ipynb"),
                             course=str(hub.course), course_file=str(hub.course / "source" / "solution.py"),
                             package=str(REPO / "mt_widgets"))
    run = hub.run_in_kernel(me, code)
    assert run["error"] is None and not run["died"], run
    probe = json.loads(run["stdout"].strip().splitlines()[-1])
    account = pwd.getpwnam(me)
    assert probe["uid"] == probe["euid"] == account.pw_uid != 0
    assert grp.getgrnam(TEST_INSTRUCTORS).gr_gid not in probe["groups"]
    assert probe["own_progress_lines"] >= 1  # the student's own progress is recorded
    # A student's kernel is the students' spec: ipykernel without its debugger (mt_hub_kernel.py).
    # (A kernel forked from the student's kernel template carries its command as its process title:
    # one string, mt_widgets/kernels/template.py.)
    assert "-m mt_hub_kernel -f " in " ".join(probe["kernel_command"]), probe["kernel_command"]
    assert probe["debugger_loaded"] is False
    assert (probe["kernel_module_list"], probe["ipkernel_sys_is_sys"]) == (0, True), probe
    denied = ["read_classmate_home", "read_classmate_file", "list_class_folder", "read_classmate_progress",
              "append_classmate_progress", "take_classmate_lock", "list_course", "read_course_source",
              "write_package", "write_stdlib", "become_root"]
    assert {key: probe[key] for key in denied} == {key: "denied" for key in denied}
    assert not (REPO / "mt_widgets" / "planted.py").exists()
    # Every process of the student's runs as the student, in the student's cgroups.
    processes = hub.processes(me)
    assert len(processes) >= 2 and all(p.uids().effective == account.pw_uid for p in processes)
    for process in processes:  # the server, its kernel template and the kernel (all forked)
        memory_group = next(line.split(":", 2)[2] for line in Path(f"/proc/{process.pid}/cgroup").read_text()
                            .splitlines() if ":memory:" in line)
        assert memory_group.endswith(f"/{hub.cgroup}/{me}"), (process, memory_group)
    # The server was forked from the class's server template, the kernel from the student's own
    # kernel template (mt_widgets/kernels/server_template.py), not started the usual way.
    assert f"{me}'s server forked from the server template" in hub.tail(2_000_000)
    titles = [" ".join(process.cmdline()).strip() for process in processes]
    assert sum(title == "mt-widgets kernel template" for title in titles) == 1, titles
    home = hub.homes / me
    assert oct(home.stat().st_mode & 0o777) == "0o700" and home.stat().st_uid == account.pw_uid


@pytest.mark.timeout(300)
def test_a_runaway_allocation_is_stopped_by_the_memory_limit_while_classmates_finish(hub):
    classmates = STUDENTS[4:7]
    for name in (RUNAWAY, *classmates):
        hub.ensure_running(name)
    runaway = "chunks = []\nwhile True:\n    chunks.append(b'x' * 2**26)\n"  # 64 MiB a step, forever

    def run(item):
        number, name = item
        return hub.run_in_kernel(name, runaway if name == RUNAWAY else EPISODE_CODE.format(number=number))

    with ThreadPoolExecutor(4) as pool:
        runs = dict(zip((RUNAWAY, *classmates), pool.map(run, enumerate((RUNAWAY, *classmates), start=4))))
    assert runs[RUNAWAY]["died"], runs[RUNAWAY]
    for name in classmates:
        assert runs[name]["error"] is None and not runs[name]["died"], runs[name]
        assert len(hub.read_json(name, "episode-result.json")["errors"]) == 3
    assert _oom_kills(hub, RUNAWAY) >= 1  # the kernel's OOM killer, inside the student's group
    assert all(_oom_kills(hub, name) == 0 for name in classmates)
    # The runaway's server survived its kernel: the student can go on.
    after = hub.run_in_kernel(RUNAWAY, "print(6 * 7)")
    assert after["stdout"].strip() == "42"


def _oom_kills(hub, name: str) -> int:
    pid = hub.processes(name)[0].pid
    group = next(line.split(":", 2)[2] for line in Path(f"/proc/{pid}/cgroup").read_text().splitlines()
                 if ":memory:" in line)
    control = Path("/sys/fs/cgroup/memory", group.lstrip("/"), "memory.oom_control").read_text()
    return int(dict(line.split() for line in control.splitlines()).get("oom_kill", 0))


@pytest.mark.timeout(1200)
def test_a_class_of_thirty_logs_in_at_once_and_every_episode_completes(hub, browser, artifacts):
    started = time.perf_counter()
    with ThreadPoolExecutor(len(STUDENTS)) as pool:
        list(pool.map(lambda name: hub.login(name, password_of(name)), STUDENTS))
    login_wall = time.perf_counter() - started
    for name in DRAWERS:
        _page(hub.homes / name, "draw.ipynb", DRAW_PAGE, name)
    shutil.copy(REPO / "notebooks" / "class_view.ipynb", hub.homes / INSTRUCTOR / "class_view.ipynb")
    os.chown(hub.homes / INSTRUCTOR / "class_view.ipynb", pwd.getpwnam(INSTRUCTOR).pw_uid, -1)

    started = time.perf_counter()
    waiting = [name for name in STUDENTS if not (hub.api("GET", f"/users/{name}").get("servers") or {}).get("")]
    spawn = hub.spawn_class(waiting)
    spawn_wall = time.perf_counter() - started

    with ThreadPoolExecutor(len(STUDENTS)) as pool:
        # Thirty kernels importing and teaching at once on two cores: minutes on a loaded machine
        # (CPU, not a lost kernel: a kernel that dies or errs fails the test at once).
        runs = dict(zip(STUDENTS, pool.map(lambda item: hub.run_in_kernel(item[1], EPISODE_CODE.format(
            number=item[0] % 12), timeout=900), enumerate(STUDENTS))))
    results = {}
    for name, run in runs.items():
        assert run["error"] is None and not run["died"], f"{name}: {run}"
        results[name] = hub.read_json(name, "episode-result.json")
        # Each student's numba cache is their own, in their home.
        assert results[name]["numba_cache"] == str(hub.homes / name / ".cache" / "numba")
        assert len(results[name]["errors"]) == 3
    assert max(results["mtt-s00"]["errors"]) < 1e-10  # no slip: taught exactly
    assert all(min(results[n]["errors"]) > 1e-3 for n in STUDENTS[1:12])
    memory = {name: hub.memory(name) for name in STUDENTS}

    # Two students draw an arrow in Chromium, logged in through the hub with their own passwords.
    for name in DRAWERS:
        context, page = local_page(browser, 1200, 1000)
        try:
            page.goto(f"{hub.url}/hub/login", timeout=60_000)
            page.fill("input[name=username]", name)
            page.fill("input[name=password]", password_of(name))
            page.click("input[type=submit], button[type=submit]")
            page.wait_for_url("**/user/**", timeout=120_000)
            page.goto(hub.user_url(name, "/voila/render/draw.ipynb"), timeout=120_000)
            page.locator("canvas").first.wait_for(timeout=120_000)
            ee = hub.draw_start
            page.wait_for_timeout(500)
            drag(page, 0, ee, (ee[0] + 60, ee[1] - 40))
            page.get_by_role("button", name="Confirm").click()
            page.wait_for_function("() => document.body.innerText.includes('confirmed 1')", timeout=60_000)
            page.screenshot(path=artifacts(f"{name}-drew"))
        finally:
            context.close()

    # The class folder holds every student the hub or class_admin.py prepared, those not started yet
    # with no events; the leaver's file stays (recorded work is kept when someone leaves).
    # (The late student is there when the roster test, which adds them, ran first.)
    roster_students = [*STUDENTS, GUESSED, RUNAWAY, LEAVER, *([LATE] if LATE in hub.students else [])]
    progress = summarise(read_class(hub.class_folder))
    assert len(progress.students) == len(roster_students) and progress.problems == []
    drawn = [e for s in read_class(hub.class_folder).students.values() for e in s.events
             if e["kind"] == "demonstration" and e.get("method") == "pointer"]
    assert len(drawn) == 2 and {e["lesson"] for e in drawn} == {"hub-draw"}
    recorded = sorted(e["theta_error"] for s in read_class(hub.class_folder).students.values() for e in s.events
                      if e["kind"] == "episode" and e["lesson"] == "hub-episode")
    returned = sorted(error for r in results.values() for error in r["errors"])
    # Every episode of the thirty is recorded (earlier tests' episodes are recorded too).
    assert Counter(returned) <= Counter(recorded) and len(returned) == 3 * len(STUDENTS)

    # The instructor opens the class view on the hub: every student is there.
    hub.ensure_running(INSTRUCTOR)
    context, page = local_page(browser, 1400, 1300)
    try:
        page.goto(f"{hub.url}/hub/login", timeout=60_000)
        page.fill("input[name=username]", INSTRUCTOR)
        page.fill("input[name=password]", INSTRUCTOR_PASSWORD)
        page.click("input[type=submit], button[type=submit]")
        page.wait_for_url("**/user/**", timeout=120_000)
        page.goto(hub.user_url(INSTRUCTOR, "/voila/render/class_view.ipynb"), timeout=120_000)
        page.wait_for_function("() => (document.querySelector('.class-status') || {}).textContent"
                               f"?.includes('{len(roster_students)} students')", timeout=120_000)
        assert page.locator("tr.student-row").count() == len(roster_students)
        page.screenshot(path=artifacts("class-view"), full_page=True)
    finally:
        context.close()

    # Nothing was written into the installation (bytecode off, numba's cache in the homes).
    assert _files(REPO / "mt_widgets") == hub.installed_before

    spawn_times = sorted(spawn.values())
    latencies = sorted(latency for r in results.values() for latency in r["latencies_s"])
    print(f"\nclass of {len(STUDENTS)}: logged in at once in {login_wall:.1f} s; {len(waiting)} spawned in "
          f"{spawn_wall:.1f} s (p50 {statistics.median(spawn_times):.1f} s, max {spawn_times[-1]:.1f} s); "
          f"feedback latency all at once p50 {statistics.median(latencies) * 1000:.0f} ms, "
          f"max {latencies[-1] * 1000:.0f} ms; "
          f"memory per student {statistics.median(memory.values()) / 2**20:.0f} MiB; "
          f"load average {os.getloadavg()[0]:.1f}")


@pytest.mark.timeout(600)
def test_the_nbgrader_exchange_works_on_the_hub_and_keeps_submissions_apart(hub):
    # The instructor works as a real one does: logged in to the hub (their server gives them their
    # numba cache, as everyone's), with nbgrader run as their own system user, never root, in a
    # course folder only instructors reach. Grading records no progress (no class folder).
    hub.ensure_running(INSTRUCTOR)
    teacher = pwd.getpwnam(INSTRUCTOR)
    course = hub.course / "mt-widgets"

    def as_instructor(*argv):
        result = hub.run_as(INSTRUCTOR, argv, cwd=course if course.exists() else hub.course,
                            MT_WIDGETS_CLASS_FOLDER=None)
        assert result.returncode == 0, f"{argv}: {result.stdout}{result.stderr}"
        return result

    as_instructor("python", "-c", "import shutil; shutil.copytree({!r}, {!r}, ignore=shutil.ignore_patterns("
                  "'gradebook.db', 'release', 'submitted', 'autograded', 'feedback', '.ipynb_checkpoints'))"
                  .format(str(REPO / "course"), str(course)))
    for step in (("generate_assignment", ASSIGNMENT, "--force"), ("release_assignment", ASSIGNMENT, "--force")):
        as_instructor("nbgrader", *step)
    outbound = hub.exchange / "mt-widgets" / "outbound" / ASSIGNMENT
    assert outbound.stat().st_uid == teacher.pw_uid  # released by the instructor's own user
    submitters = {STUDENTS[8]: "solution", STUDENTS[9]: "untouched"}
    for name in submitters:
        hub.ensure_running(name)
    ids = {"course_id": "mt-widgets", "assignment_id": ASSIGNMENT}
    for name, kind in submitters.items():
        listing = hub.server_api(name, "POST", "/assignments/fetch", data=ids)
        assert listing["success"], listing
        assert any(a["assignment_id"] == ASSIGNMENT and a["status"] == "fetched" for a in listing["value"]), listing
        path = f"/api/contents/{ASSIGNMENT}/{ASSIGNMENT}.ipynb"
        fetched = hub.server_api(name, "GET", path)
        assert fetched["type"] == "notebook"
        if kind == "solution":  # the student "works": saves the notebook through the contents API
            fetched["content"]["cells"] = [c for c in source_notebook(ASSIGNMENT).cells]
            hub.server_api(name, "PUT", path, json={"type": "notebook", "format": "json",
                                                   "content": fetched["content"]})
        submitted = hub.server_api(name, "POST", "/assignments/submit", data=ids)
        assert submitted["success"], submitted
        assert any(a["status"] == "submitted" for a in submitted["value"]), submitted
    # A student cannot see what classmates submitted (nbgrader's inbound: write, no listing).
    inbound = hub.exchange / "mt-widgets" / "inbound"
    peek = hub.run_in_kernel(STUDENTS[9], f"import os\ntry:\n    print(os.listdir({str(inbound)!r}))\n"
                                          "except PermissionError:\n    print('denied')\n")
    assert peek["stdout"].strip() == "denied", peek
    assert {p.stat().st_uid for p in inbound.iterdir()} == {pwd.getpwnam(n).pw_uid for n in submitters}
    for step in (("collect", ASSIGNMENT), ("autograde", ASSIGNMENT, "--create"), ("generate_feedback", ASSIGNMENT),
                 ("release_feedback", ASSIGNMENT)):
        as_instructor("nbgrader", *step)
    assert sorted(p.name for p in (course / "submitted").iterdir()) == sorted(submitters)
    # Everything grading made is the instructor's, inside a course folder closed to others (nbgrader
    # sets some files' modes itself: the folder, not each file, keeps students out).
    made = [course / "gradebook.db", *(course / "autograded").rglob("*"), *(course / "feedback").rglob("*")]
    assert made and {p.stat().st_uid for p in made} == {teacher.pw_uid}
    assert hub.course.stat().st_mode & 0o007 == 0
    # A student's kernel cannot read the gradebook nor a classmate's graded notebook.
    graded = next((course / "autograded" / STUDENTS[8]).rglob("*.ipynb"))
    peek = hub.run_in_kernel(STUDENTS[9], "for path in ({!r}, {!r}):\n    try:\n        open(path).read()\n"
                                          "        print('read')\n    except PermissionError:\n"
                                          "        print('denied')\n".format(str(course / "gradebook.db"),
                                                                            str(graded)))
    assert peek["stdout"].split() == ["denied", "denied"], peek
    for name, kind in submitters.items():
        fetched = hub.server_api(name, "POST", "/assignments/fetch_feedback", data=ids)
        assert fetched["success"], fetched
        feedback = list((hub.homes / name / ASSIGNMENT / "feedback").rglob(f"{ASSIGNMENT}.html"))
        assert len(feedback) == 1, f"{name} got no feedback"
        html = feedback[0].read_text()
        # a1: 10 autograded points and a written answer (2) the instructor grades by hand later.
        score = "10.0 / 12.0" if kind == "solution" else "0.0 / 12.0"
        assert f"Score: {score}" in html.replace("&nbsp;", " ") or score in html, html[:2000]


def _hub_tree(hub) -> set[int]:
    """The hub process and everything under it now (proxy, services, server template, servers, kernels)."""
    process = psutil.Process(hub.process.pid)
    return {process.pid, *(child.pid for child in process.children(recursive=True))}


def _proxy_pid(hub) -> int:
    return int((hub.root / "state" / "proxy.pid").read_text())


def _kill_proxy(hub) -> float:
    """The proxy alone killed: the hub finds it gone, starts it again and gives it every route back."""
    started = time.monotonic()
    os.kill(_proxy_pid(hub), signal.SIGKILL)
    return hub.wait_until_answering(started)


#: A cell a student runs in JupyterLab again and again: which run it is and in which kernel process.
COUNTED_RUN = "import os\nruns = globals().get('runs', 0) + 1\nprint(f'run {runs} in {os.getpid()}')"


def _open_lab(hub, browser, name: str, notebook: str):
    """``name`` logs in with their password and opens ``notebook`` in JupyterLab: (context, page)."""
    context, page = local_page(browser, 1200, 900)
    page.goto(f"{hub.url}/hub/login", timeout=60_000)
    page.fill("input[name=username]", name)
    page.fill("input[name=password]", password_of(name))
    page.click("input[type=submit], button[type=submit]")
    page.wait_for_url("**/user/**", timeout=120_000)
    page.goto(hub.user_url(name, f"/lab/tree/{notebook}"), timeout=120_000)
    page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=120_000)
    return context, page


def _run_counted(page, run: int, timeout_ms: float, artifacts) -> str:
    """Runs the page's first cell (``COUNTED_RUN``) and waits for its ``run``-th output; the output."""
    page.locator(".jp-Notebook .jp-Cell").first.locator(".jp-InputArea-editor").click()
    page.keyboard.press("Control+Enter")
    output = page.locator(".jp-Notebook .jp-Cell").first.locator(".jp-OutputArea")
    try:
        page.wait_for_function("(run) => [...document.querySelectorAll('.jp-OutputArea')].some("
                               "o => o.innerText.includes(`run ${run} in`))", arg=run, timeout=timeout_ms)
    except Exception:
        page.screenshot(path=artifacts(f"student-page-run-{run}-not-done"))
        raise AssertionError(f"the student's cell did not give its run {run} within {timeout_ms / 1000:.0f} s; "
                             f"the page shows: {page.locator('body').inner_text()[-600:]!r}") from None
    return output.inner_text()


@pytest.mark.timeout(900)
def test_thirty_students_mid_episode_keep_server_and_kernel_across_a_hub_restart_a_hub_kill_and_a_proxy_restart(
        hub, browser, artifacts):
    """Issue 46: thirty students, each mid-episode (a kernel holding the episode), through three faults
    in turn: the hub stopped the documented way (SIGTERM) and started again, the hub killed (SIGKILL)
    and started again, the proxy killed alone. After each, every student's server is the same process
    (re-adopted by the pid in the hub's database), and every student's next demonstration, sent at
    once by all thirty, runs in the very same kernel, which still holds its variables, and is done
    within 10 s of the hub answering again. Nothing the old hub started is left behind (its server
    template and services end with it; only the proxy outlives a killed hub, and the new hub adopts
    it). After the class ends no process of any student is left, zombie or not.

    The module's class of thirty is reused (its servers are running after the class test; alone, this
    starts them), so the three faults cost about a minute on two cores.

    Meanwhile one of them has a notebook open in JupyterLab in Chromium: they run a cell while the hub
    is down (it answers: the proxy and their server are up, and their login is their server's to
    check), and after each fault the same page, never reloaded, runs it again in the same kernel
    (after the proxy's restart JupyterLab reconnects its kernel's websocket by itself)."""
    users = {user["name"]: user for user in hub.api("GET", "/users")}
    if set(STUDENTS) - set(users):
        hub.create_users(sorted(set(STUDENTS) - set(users)))
    waiting = [name for name in STUDENTS if not ((users.get(name) or {}).get("servers") or {}).get("")]
    if waiting:
        hub.spawn_class(waiting)
    with ThreadPoolExecutor(len(STUDENTS)) as pool:
        begun = dict(zip(STUDENTS, pool.map(lambda name: hub.run_in_kernel(name, MID_EPISODE.format(name=name),
                                                                           timeout=600), STUDENTS)))
    for name, answer in begun.items():
        assert answer["error"] is None and not answer["died"], (name, answer)
    kernels = {name: answer["kernel_id"] for name, answer in begun.items()}
    servers = {name: hub.api("GET", f"/users/{name}")["servers"][""]["state"]["pid"] for name in STUDENTS}

    def next_demonstration(name: str, back: float) -> tuple[dict, float]:
        answer = hub.run_in_kernel(name, NEXT_DEMONSTRATION, timeout=30, kernel_id=kernels[name])
        return answer, time.monotonic() - back

    watcher = STUDENTS[2]
    _page(hub.homes / watcher, "restart.ipynb", COUNTED_RUN, watcher)
    context, page = _open_lab(hub, browser, watcher, "restart.ipynb")
    page_runs = [_run_counted(page, 1, 120_000, artifacts)]

    def stopped_and_tried(signum: int) -> float:
        hub.end(signum)
        # While the hub is down, the student runs their cell: the page answers as before.
        page_runs.append(_run_counted(page, len(page_runs) + 1, 60_000, artifacts))
        page.screenshot(path=artifacts("student-page-hub-down"))
        return hub.start_again()

    faults = {"hub stopped (SIGTERM)": lambda: stopped_and_tried(signal.SIGTERM),
              "hub killed (SIGKILL)": lambda: hub.restart(signal.SIGKILL),
              "proxy killed": lambda: _kill_proxy(hub)}
    figures = {}
    try:
        for fault, act in faults.items():
            figures[fault] = _through_fault(hub, fault, act, next_demonstration, servers)
            started = time.monotonic()
            page_runs.append(_run_counted(page, len(page_runs) + 1, 60_000, artifacts))
            figures[fault] += (time.monotonic() - started,)
            page.screenshot(path=artifacts(f"student-page-after-{'-'.join(fault.split()[:2])}"))
        # A class's JupyterLab asks no student about Jupyter's news (student-config/labconfig): a popup
        # over a phone's screen, and a request from every student's page to jupyter.org.
        assert "Jupyter news" not in page.locator("body").inner_text()
    finally:
        context.close()
    kernel_pids = {line.split(" in ")[-1].strip() for line in page_runs}
    assert len(kernel_pids) == 1, f"the student's page ran its cell in more than one kernel: {page_runs}"

    # The class ends: every server stopped through the hub; nothing of any student stays behind.
    with ThreadPoolExecutor(8) as pool:
        list(pool.map(lambda name: hub.api("DELETE", f"/users/{name}/server"), STUDENTS))
    deadline = time.monotonic() + 60
    while _class_processes(hub) and time.monotonic() < deadline:
        time.sleep(0.5)
    left = [(p.pid, p.status()) for p in _class_processes(hub)]
    assert left == [], f"processes (zombies included) of students after the class ended: {left}"
    print("\nthirty mid-episode: " + "; ".join(
        f"{fault}: hub back in {down_s:.1f} s, every next demonstration done {slowest_s:.1f} s after, the "
        f"student's JupyterLab page ran its cell {page_s:.1f} s after"
        for fault, (down_s, slowest_s, page_s) in figures.items()))


def _through_fault(hub, fault: str, act, next_demonstration, servers) -> tuple[float, float]:
    """One fault (``act``) with thirty students mid-episode: (seconds until the hub answered again,
    seconds after that until every next demonstration was done)."""
    before, proxy = _hub_tree(hub), _proxy_pid(hub)
    down_s = act()
    back = time.monotonic()
    with ThreadPoolExecutor(len(STUDENTS)) as pool:
        answers = dict(zip(STUDENTS, pool.map(next_demonstration, STUDENTS, [back] * len(STUDENTS))))
    for name, (answer, after_s) in answers.items():
        assert answer == {**answer, "stdout": f"{name}\n", "error": None, "died": False}, (fault, name, answer)
        assert after_s < 10, f"{fault}: {name}'s next demonstration came {after_s:.1f} s after the hub was back"
    assert {name: hub.api("GET", f"/users/{name}")["servers"][""]["state"]["pid"] for name in STUDENTS} == servers
    # What the old hub started and nobody adopted: an orphan (members' servers and kernels, the
    # instructor's included, and an adopted proxy are meant to outlive it).
    members_now = {p.pid for p in _class_processes(hub, [*hub.students, *hub.admins])}
    adopted = _hub_tree(hub) | members_now | ({proxy} if _proxy_pid(hub) == proxy else set())
    orphans = [p for p in map(_alive, before - adopted) if p is not None]
    assert orphans == [], f"{fault} left {[(p.pid, p.cmdline()) for p in orphans]}"
    return down_s, max(after_s for _, after_s in answers.values())


def _alive(pid: int) -> psutil.Process | None:
    """The process ``pid`` if it still exists (a zombie too), else None."""
    try:
        return psutil.Process(pid)
    except psutil.NoSuchProcess:
        return None


def _class_processes(hub, names=STUDENTS) -> list[psutil.Process]:
    """Every process of ``names``' system users (zombies too: psutil lists them); a login whose
    account is gone (the leaver) has none."""
    found = []
    for name in names:
        try:
            found.extend(hub.processes(name))
        except KeyError:
            continue
    return found
