"""deploy/jupyterhub/jupyterhub_config.py loaded without starting a hub, and its Zero to JupyterHub twin.

Loading the config prepares the roster's accounts (system users ``mtt-cfg-...``), so these tests
run as root, like the hub, and remove what they made.
"""

from __future__ import annotations

import asyncio
import grp
import json
import os
import pwd
import secrets
import shutil
import stat
import subprocess
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import SimpleNamespace

import psutil
import pytest
import yaml
from jupyterhub.spawner import LocalProcessSpawner
from traitlets.config.loader import PyFileConfigLoader

from .course_support import REPO
from .hub_support import STUDENT_PYTHON

HUB = REPO / "deploy" / "jupyterhub"
CONFIG = HUB / "jupyterhub_config.py"
sys.path.insert(0, str(HUB))
import class_hub  # noqa: E402
from roster_authenticator import RosterAuthenticator  # noqa: E402

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="the class hub's config makes system users: run as root")

TEACHER, ANN = "mtt-cfg-teacher", "mtt-cfg-ann"
GROUP = "mtt-cfg-instructors"


def in_a_loop_of_its_own(coroutine):
    """Run ``coroutine`` to its end in a new event loop on a thread of its own: in the hub tier the
    browser fixture's Playwright keeps an event loop running in the main thread, where
    ``asyncio.run`` refuses to start another."""
    with ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, coroutine).result()


def _remove_accounts():
    for user in pwd.getpwall():
        if user.pw_name.startswith("mtt-cfg-"):
            subprocess.run(["userdel", user.pw_name], capture_output=True, timeout=60)
    subprocess.run(["groupdel", GROUP], capture_output=True, timeout=60)


@pytest.fixture
def setting(tmp_path, monkeypatch):
    """Loads the config with a two-person roster; returns a function (more env -> config)."""
    cgroup = f"mtt-cfg-{secrets.token_hex(3)}"
    runtime = Path("/tmp", cgroup)
    roster = tmp_path / "roster.csv"
    roster.write_text(f"login,role\n{TEACHER},instructor\n{ANN},\n")
    python = STUDENT_PYTHON if STUDENT_PYTHON.exists() else Path(sys.executable)
    base = {"MT_HUB_ROSTER": str(roster), "MT_HUB_STATE": str(tmp_path / "state"),
            "MT_HUB_HOMES": str(tmp_path / "homes"), "MT_HUB_RUNTIME": str(runtime),
            "MT_HUB_INSTRUCTORS_GROUP": GROUP, "MT_HUB_CGROUP": cgroup, "MT_HUB_STUDENT_PYTHON": str(python),
            "MT_WIDGETS_CLASS_FOLDER": str(tmp_path / "class"), "MT_WIDGETS_EXCHANGE": "/srv/exchange"}

    def load(**env):
        for name, value in {**base, **env}.items():
            monkeypatch.setenv(name, value)
        return PyFileConfigLoader(CONFIG.name, path=str(CONFIG.parent)).load_config()

    load.roster, load.tmp, load.cgroup = roster, tmp_path, cgroup
    yield load
    _remove_accounts()
    shutil.rmtree(runtime, ignore_errors=True)
    for controller in ("memory", "cpu"):
        for group in sorted(Path("/sys/fs/cgroup", controller).rglob(cgroup), reverse=True):
            for child in group.iterdir():
                if child.is_dir():
                    child.rmdir()
            group.rmdir()


def _spawner(config, name, tmp_path, admin=False):
    return SimpleNamespace(user=SimpleNamespace(name=name, admin=admin), port=0, log=SimpleNamespace(
        warning=lambda *a: None), home_dir=str(tmp_path / "homes" / name))


def test_the_hub_listens_on_loopback_with_the_roster_authenticator_and_each_students_own_user(setting):
    config = setting(MT_HUB_PORT="8123")
    assert config.JupyterHub.ip == config.JupyterHub.hub_ip == "127.0.0.1"
    assert config.ConfigurableHTTPProxy.api_url.startswith("http://127.0.0.1:")
    assert config.JupyterHub.port == 8123
    assert config.JupyterHub.authenticator_class is RosterAuthenticator or \
        config.JupyterHub.authenticator_class.__name__ == "RosterAuthenticator"
    assert "allow_all" not in config.Authenticator
    assert config.Authenticator.admin_users == {TEACHER}
    assert issubclass(config.JupyterHub.spawner_class, LocalProcessSpawner)
    assert "--allow-root" not in config.Spawner.get("args", [])
    assert config.Spawner.cmd[1:] == ["-m", "jupyterhub.singleuser"]
    culler = next(s for s in config.JupyterHub.services if s["name"] == "idle-culler")
    assert f"--timeout={class_hub.DEFAULT_CULL_IDLE_S}" in culler["command"]
    assert culler["command"][1].endswith("idle_culler.py")  # ended with its hub, even a killed one


def test_loading_the_config_makes_each_roster_login_a_private_system_user(setting):
    setting()
    for login, admin in ((TEACHER, True), (ANN, False)):
        user = pwd.getpwnam(login)
        assert user.pw_uid != 0 and user.pw_gecos == class_hub.MARKER
        home = Path(user.pw_dir)
        assert home == setting.tmp / "homes" / login
        assert stat.S_IMODE(home.stat().st_mode) == 0o700 and home.stat().st_uid == user.pw_uid
        assert (login in grp.getgrnam(GROUP).gr_mem) == admin
    # The class folder: only instructors list it; each student's file is theirs, made before they start.
    folder = setting.tmp / "class"
    assert stat.S_IMODE(folder.stat().st_mode) == class_hub.CLASS_FOLDER_MODE
    assert folder.stat().st_gid == grp.getgrnam(GROUP).gr_gid
    files = [p for p in folder.glob("*.jsonl")]
    assert len(files) == 1 and files[0].stat().st_uid == pwd.getpwnam(ANN).pw_uid
    assert stat.S_IMODE(files[0].stat().st_mode) == 0o640


def test_a_roster_login_that_is_someone_elses_system_user_is_refused(setting):
    subprocess.run(["useradd", "--no-create-home", "mtt-cfg-other"], check=True, timeout=60)
    setting.roster.write_text("login\nmtt-cfg-other\n")
    with pytest.raises(class_hub.ClassHubError, match="was not made by the class hub"):
        setting()


def test_a_bad_roster_stops_the_hub_naming_the_line(setting):
    setting.roster.write_text("login,role\nann,student\nann,student\nroot,\n")
    with pytest.raises(ValueError, match=r"line 3: duplicate login 'ann'.*\n.*line 4: login 'root' is reserved"):
        setting()
    assert "mtt-cfg" not in " ".join(u.pw_name for u in pwd.getpwall())


def test_the_spawn_hook_gives_a_warm_cache_a_runtime_folder_cgroups_and_a_port_outside_the_ephemeral_range(setting):
    template = setting.tmp / "template"
    (template / "core_x").mkdir(parents=True)
    (template / "core_x" / "f.nbi").write_text("index")
    config = setting(MT_HUB_NUMBA_TEMPLATE=str(template), MT_HUB_MEM_LIMIT="700M", MT_HUB_CPU_LIMIT="0.5")
    spawner = _spawner(config, ANN, setting.tmp)
    in_a_loop_of_its_own(config.Spawner.pre_spawn_hook(spawner))
    ann = pwd.getpwnam(ANN)
    cached = setting.tmp / "homes" / ANN / ".cache" / "numba" / "core_x" / "f.nbi"
    assert cached.read_text() == "index" and cached.stat().st_uid == ann.pw_uid
    assert 20000 <= spawner.port < 32768
    runtime = Path("/tmp", setting.cgroup, ANN)
    assert runtime.stat().st_uid == ann.pw_uid and stat.S_IMODE(runtime.stat().st_mode) == 0o700
    memory = next(Path("/sys/fs/cgroup/memory").rglob(f"{setting.cgroup}/{ANN}"))
    cpu = next(Path("/sys/fs/cgroup/cpu").rglob(f"{setting.cgroup}/{ANN}"))
    assert int((memory / "memory.limit_in_bytes").read_text()) == 700 * 2**20
    assert int((cpu / "cpu.cfs_quota_us").read_text()) == int((cpu / "cpu.cfs_period_us").read_text()) // 2
    cached.write_text("the student's own")
    in_a_loop_of_its_own(config.Spawner.pre_spawn_hook(spawner))  # a restart keeps the student's cache
    assert cached.read_text() == "the student's own"
    config.Spawner.post_stop_hook(spawner)
    assert not memory.exists() and not cpu.exists()
    # Someone taken off the roster does not start again.
    setting.roster.write_text(f"login,role\n{TEACHER},instructor\n")
    with pytest.raises(class_hub.ClassHubError, match="no longer on the roster"):
        in_a_loop_of_its_own(config.Spawner.pre_spawn_hook(spawner))


def test_the_warm_caches_copy_leaves_the_hubs_event_loop_serving_others(setting, monkeypatch):
    """The copy runs in a thread: while it is under way, another coroutine of the hub's loop runs.
    The copy here waits until that coroutine has run; on the loop itself it would wait in vain."""
    template = setting.tmp / "template"
    (template / "core_x").mkdir(parents=True)
    (template / "core_x" / "f.nbi").write_text("index")
    config = setting(MT_HUB_NUMBA_TEMPLATE=str(template))
    hooks = config.Spawner.pre_spawn_hook.__globals__
    copy, others_served, seen = hooks["_copy_owned"], threading.Event(), []

    def slow_copy(*args):
        seen.append(others_served.wait(10))
        copy(*args)

    monkeypatch.setitem(hooks, "_copy_owned", slow_copy)

    async def another_login():
        await asyncio.sleep(0)
        others_served.set()

    async def spawn_and_login():
        await asyncio.gather(config.Spawner.pre_spawn_hook(_spawner(config, ANN, setting.tmp)), another_login())

    in_a_loop_of_its_own(spawn_and_login())
    assert seen == [True], "the hub's loop stood still while the cache was copied"
    cached = setting.tmp / "homes" / ANN / ".cache" / "numba"
    assert (cached / "core_x" / "f.nbi").read_text() == "index"
    assert [p.name for p in cached.parent.iterdir()] == ["numba"]  # no half-copied folder left beside it
    config.Spawner.post_stop_hook(_spawner(config, ANN, setting.tmp))


def test_a_copy_cut_short_leaves_no_cache_and_the_next_spawn_copies_again(setting, monkeypatch):
    template = setting.tmp / "template"
    (template / "core_x").mkdir(parents=True)
    (template / "core_x" / "f.nbi").write_text("index")
    config = setting(MT_HUB_NUMBA_TEMPLATE=str(template))
    hooks = config.Spawner.pre_spawn_hook.__globals__
    spawner = _spawner(config, ANN, setting.tmp)

    def disk_full(source, target, *args, **kwargs):
        raise OSError(28, "No space left on device", str(target))

    with monkeypatch.context() as patch:
        patch.setattr(hooks["shutil"], "copyfile", disk_full)
        with pytest.raises(OSError, match="No space left on device"):
            in_a_loop_of_its_own(config.Spawner.pre_spawn_hook(spawner))
    cache_folder = setting.tmp / "homes" / ANN / ".cache"
    assert list(cache_folder.iterdir()) == []
    in_a_loop_of_its_own(config.Spawner.pre_spawn_hook(spawner))
    assert (cache_folder / "numba" / "core_x" / "f.nbi").read_text() == "index"
    config.Spawner.post_stop_hook(spawner)


def test_students_spawned_at_once_never_share_a_port(setting):
    """Each server's port is kept for its login from the spawn until the server stops: a free port is
    free only until a server binds it, and a class is given its ports before any server binds one."""
    hooks = setting().Spawner.pre_spawn_hook.__globals__
    reserve, release = hooks["_reserve_port"], hooks["_release_port"]
    logins = [f"student{n:03d}" for n in range(400)]
    ports = [reserve(login) for login in logins]  # a large class, nobody's server bound yet
    assert len(set(ports)) == len(ports) and all(20000 <= port < 32768 for port in ports)
    # A restart may get any free port, but never a port another login holds.
    again = reserve(logins[0])
    assert again not in ports[1:]
    release(logins[1])
    assert logins[1] not in hooks["_SERVER_PORTS"] and hooks["_SERVER_PORTS"][logins[0]] == again
    for login in logins:
        release(login)
    assert hooks["_SERVER_PORTS"] == {}


def test_each_students_caches_and_runtime_are_their_own_and_nothing_writes_into_the_install(setting):
    config = setting()
    environment = config.Spawner.environment
    spawner = _spawner(config, ANN, setting.tmp)
    assert environment["NUMBA_CACHE_DIR"](spawner) == str(setting.tmp / "homes" / ANN / ".cache" / "numba")
    assert environment["JUPYTER_RUNTIME_DIR"](spawner) == str(Path("/tmp", setting.cgroup, ANN))
    assert environment["PYTHONDONTWRITEBYTECODE"] == "1"
    assert environment["PYTHONPATH"].split(os.pathsep)[0] == str(HUB / "student-site")
    assert "node" not in os.listdir(environment["PATH"](spawner))  # JupyterLab would run yarn at every start
    assert environment["MT_WIDGETS_CLASS_FOLDER"] == str(setting.tmp / "class")
    assert environment["MT_WIDGETS_EXCHANGE"] == "/srv/exchange"
    assert environment["MT_HUB_ROLE"](spawner) == "student"
    assert environment["MT_HUB_ROLE"](_spawner(config, TEACHER, setting.tmp, admin=True)) == "instructor"
    for name in ("nbgrader_config.py", "jupyter_server_config.py"):
        assert Path(environment["JUPYTER_CONFIG_PATH"], name).is_file()


def _server_config(role: str):
    os.environ["MT_HUB_ROLE"] = role
    try:
        return PyFileConfigLoader("jupyter_server_config.py", path=str(HUB / "student-config")).load_config()
    finally:
        os.environ.pop("MT_HUB_ROLE")


def test_students_servers_use_ipc_kernels_and_leave_out_what_lessons_do_not_use():
    student = _server_config("student")
    assert student.KernelManager.transport == "ipc"
    assert student.ServerApp.terminals_enabled is False
    off = {name for name, enabled in student.ServerApp.jpserver_extensions.items() if not enabled}
    assert off == {"jupyter_lsp", "jupyter_server_terminals", "nbgrader.server_extensions.formgrader",
                   "nbgrader.server_extensions.assignment_list", "nbgrader.server_extensions.validate_assignment",
                   "nbgrader.server_extensions.course_list", "voila.server_extension", "notebook", "notebook_shim"}
    # nbgrader's student side and Voila's pages instead come from student-site/, loaded at first use.
    for lazy in ("mt_hub_nbgrader", "mt_hub_voila"):
        assert student.ServerApp.jpserver_extensions[lazy] is True
        assert (HUB / "student-site" / f"{lazy}.py").is_file()
    # Students' kernels (student-share/ first on their JUPYTER_PATH): ipykernel without its debugger.
    spec = json.loads((HUB / "student-share" / "kernels" / "python3" / "kernel.json").read_text())
    assert spec["argv"][:3] == ["{prefix}/bin/python", "-m", "mt_hub_kernel"] and spec["metadata"]["debugger"] is False
    # ...and without IPython's SQLite history (a file and a thread per kernel, for past sessions' input).
    assert "--HistoryManager.enabled=False" in spec["argv"]
    assert (HUB / "student-site" / "mt_hub_kernel.py").is_file()
    # For everyone: activity read from the headers, extensions listed without PyPI's client.
    for config in (student, _server_config("instructor")):
        assert config.ServerApp.kernel_manager_class == "mt_widgets.kernels.activity.HeaderActivityKernelManager"
        assert config.LabApp.extension_manager == "readonly"
    instructor = _server_config("instructor")
    assert instructor.KernelManager.transport == "ipc"
    assert "jpserver_extensions" not in instructor.ServerApp


def test_the_server_template_is_on_unless_the_environment_says_off(setting):
    def template(config):
        return config.JupyterHub.spawner_class.start.__globals__["SERVER_TEMPLATE"]

    on = template(setting())
    shutil.rmtree(on.folder)   # its socket's folder, made when the config is read
    assert on.servers == ["jupyterhub.singleuser"] and on.kernels == ["mt_hub_kernel"]
    assert "mt_widgets.kernels.activity" in on.preload   # the server's kernel manager, imported before forking
    # Every REST handler module jupyter_server imports by name at a server's start.
    from jupyter_server.serverapp import JUPYTER_SERVICE_HANDLERS

    handlers = {module for modules in JUPYTER_SERVICE_HANDLERS.values() for module in modules or ()}
    assert handlers | {"jupyter_server.base.handlers"} <= set(on.preload)
    assert template(setting(MT_HUB_SERVER_TEMPLATE="off")) is None


def test_the_server_templates_backlog_covers_every_spawn_the_hub_lets_run_at_once(setting):
    """A backlog of 64 under a spawn limit of 100 lost a quarter of a class started at once: the
    backlog is the limit itself, so neither can change alone."""
    for env, limit in (({}, 100), ({"MT_HUB_SPAWN_LIMIT": "150"}, 150)):
        config = setting(**env)
        template = config.JupyterHub.spawner_class.start.__globals__["SERVER_TEMPLATE"]
        shutil.rmtree(template.folder)
        assert config.JupyterHub.concurrent_spawn_limit == limit
        assert template.backlog >= config.JupyterHub.concurrent_spawn_limit
        assert template.command()[0][-1] == str(template.backlog)
        # What Linux grants a listening socket at most: the backlog asked for must not be cut.
        assert int(Path("/proc/sys/net/core/somaxconn").read_text()) >= template.backlog
    for bad in ("0", "-3", "many"):
        with pytest.raises(SystemExit, match=f"MT_HUB_SPAWN_LIMIT: expected a whole number of at least 1, got '{bad}'"):
            setting(MT_HUB_SPAWN_LIMIT=bad)


def test_a_hub_stopped_or_restarted_leaves_students_servers_running(setting):
    assert setting().JupyterHub.cleanup_servers is False


def test_a_full_class_server_refuses_the_next_student_with_a_page_of_its_own(setting):
    config = setting()
    assert config.JupyterHub.active_server_limit == 100
    page = Path(config.JupyterHub.template_paths[0], "429.html")
    assert page.is_file() and "The class server is full" in page.read_text()
    assert setting(MT_HUB_SERVER_LIMIT="0").JupyterHub.active_server_limit == 0
    with pytest.raises(SystemExit, match=r"MT_HUB_SERVER_LIMIT: expected a whole number of at least 0 \(0: no limit\)"):
        setting(MT_HUB_SERVER_LIMIT="full")


def test_the_installation_check_names_the_folder_students_cannot_enter(tmp_path):
    locked = tmp_path / "locked"
    (locked / "inner").mkdir(parents=True)
    (locked / "inner" / "python").write_text("")
    os.chmod(locked / "inner" / "python", 0o755)
    os.chmod(locked, 0o700)
    problems = class_hub.installation_problems([locked / "inner" / "python"])
    assert f"students cannot enter {locked} (needed for {locked / 'inner' / 'python'}): chmod o+x {locked}" in problems
    os.chmod(locked, 0o755)
    assert not any(p.endswith(f"chmod o+x {locked}") for p in class_hub.installation_problems([locked / "inner"]))


def test_the_zero_to_jupyterhub_values_carry_the_same_authenticator_roster_isolation_and_limits():
    values = yaml.safe_load((HUB / "z2jh" / "values.yaml").read_text())
    hub = values["hub"]["config"]
    assert hub["JupyterHub"]["authenticator_class"] == "roster_authenticator.RosterAuthenticator"
    for trait in ("min_password_length", "max_failures", "lockout_seconds", "failure_delay_seconds"):
        assert hub["RosterAuthenticator"][trait] == getattr(RosterAuthenticator, trait).default_value, trait
    assert hub["RosterAuthenticator"]["roster_path"] == values["hub"]["extraEnv"]["MT_HUB_ROSTER"]
    assert "c.KubeSpawner.uid = _uid" in values["hub"]["extraConfig"]["mt-class"]  # a uid per login
    single = values["singleuser"]
    assert class_hub.parse_bytes(single["memory"]["limit"]) == class_hub.parse_bytes(class_hub.DEFAULT_MEM_LIMIT)
    assert float(single["cpu"]["limit"]) == class_hub.DEFAULT_CPU_LIMIT
    assert single["extraPodConfig"]["securityContext"]["runAsNonRoot"] is True
    assert single["extraEnv"]["PYTHONDONTWRITEBYTECODE"] == "1"
    assert values["cull"]["enabled"] is True and values["cull"]["timeout"] == class_hub.DEFAULT_CULL_IDLE_S
    dockerfile = (HUB / "z2jh" / "Dockerfile").read_text()
    assert f"COPY deploy/jupyterhub/student-config {single['extraEnv']['JUPYTER_CONFIG_PATH']}" in dockerfile
    assert f"COPY deploy/jupyterhub/student-site {single['extraEnv']['PYTHONPATH']}" in dockerfile
    assert "roster_authenticator.py" in dockerfile and "AS hub" in dockerfile and "AS singleuser" in dockerfile


def test_students_servers_leave_out_the_package_that_costs_seconds_at_every_start():
    code = ("import sys, jsonschema, jupyter_events\n"
            "jsonschema.validate({'a': 1}, {'type': 'object', 'properties': {'a': {'type': 'integer'}}})\n"
            "print('rfc3987_syntax' in sys.modules)")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(HUB / "student-site"), str(REPO)]))
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"


@pytest.mark.skipif(not Path("/sys/fs/cgroup/memory/cgroup.procs").exists(),
                    reason="the class hub's limits use cgroup v1's memory controller")
def test_what_a_killed_run_left_is_removed_and_nothing_else():
    """A CI run killed mid-way leaves its hub (a root process in the hub's folder), the hub's
    accounts with their processes, a cgroup and a folder; the next run's sweep
    (hub_support.remove_leftovers) removes them, and only them, and nothing while a hub lives."""
    import fcntl

    from .hub_support import HUB_ACCOUNT, HUB_LOCK, _own_cgroup, remove_leftovers

    assert HUB_ACCOUNT == class_hub.MARKER
    left, stranger = "mtt-left-a", "mtt-left-b"
    subprocess.run(["useradd", "--no-create-home", "--comment", HUB_ACCOUNT, left], check=True, timeout=60)
    subprocess.run(["useradd", "--no-create-home", "--comment", "someone else", stranger], check=True, timeout=60)
    name = f"mtt-hub-{secrets.token_hex(3)}"
    group = Path("/sys/fs/cgroup/memory", _own_cgroup("memory").lstrip("/"), name, "student")
    folder = Path("/tmp", name)
    sleepers = []
    try:
        group.mkdir(parents=True)
        folder.mkdir()
        account = pwd.getpwnam(left)
        # The left user's process, still running in the left cgroup, as a student's kernel would be;
        # and the killed run's hub, a root process working in the hub's folder.
        student = subprocess.Popen(["sleep", "600"], user=account.pw_uid, group=account.pw_gid)
        hub = subprocess.Popen(["sleep", "600"], cwd=folder)
        sleepers += [student, hub]
        (group / "cgroup.procs").write_text(str(student.pid))
        assert str(student.pid) in (group / "cgroup.procs").read_text().split()
        # While a hub lives (it holds the lock), nothing is swept.
        with open(HUB_LOCK, "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_SH)
            with pytest.raises(RuntimeError, match="another test hub is running"):
                remove_leftovers()
        assert student.poll() is None and hub.poll() is None and folder.exists()
        removed = remove_leftovers()
        assert left in removed and stranger not in removed
        # Killed and waited for, so userdel could go on (the sweep reaped them: no exit status is left).
        for sleeper in (student, hub):
            assert sleeper.poll() is not None and not psutil.pid_exists(sleeper.pid)
        logins = {user.pw_name for user in pwd.getpwall()}
        assert left not in logins
        assert stranger in logins  # the test prefix alone is not enough: only the hub's own accounts go
        assert not group.parent.exists()
        assert not folder.exists()
    finally:
        for sleeper in sleepers:
            sleeper.kill()
            sleeper.wait()
        for login in (left, stranger):
            subprocess.run(["userdel", login], capture_output=True, timeout=60)
        shutil.rmtree(folder, ignore_errors=True)
        for path in (group, group.parent):
            if path.exists():
                path.rmdir()


def test_one_setting_chooses_the_learning_platforms_launches_as_the_login(setting):
    platform = {"MT_HUB_LTI_ISSUER": "https://canvas.instructure.com", "MT_HUB_LTI_CLIENT_ID": "10000000000042",
                "MT_HUB_LTI_DEPLOYMENT_ID": "7:abc, 8:def",
                "MT_HUB_LTI_AUTH_URL": "https://sso.canvaslms.com/api/lti/authorize_redirect",
                "MT_HUB_LTI_JWKS_URL": "https://sso.canvaslms.com/api/lti/security/jwks"}
    config = setting(MT_HUB_LOGIN="lti", **platform)
    assert config.JupyterHub.authenticator_class.__name__ == "ClassLTIAuthenticator"
    lti = config.ClassLTIAuthenticator
    assert (lti.issuer, lti.client_id, lti.deployment_ids) == (
        "https://canvas.instructure.com", {"10000000000042"}, {"7:abc", "8:def"})
    assert lti.roster_path == str(setting.roster.resolve()) and lti.login_prefix == "lti-"
    # The roster's people are accounts as with the roster login: the isolation does not depend on the login.
    assert config.Authenticator.admin_users == {TEACHER} and pwd.getpwnam(ANN).pw_gecos == class_hub.MARKER
    with pytest.raises(SystemExit, match="MT_HUB_LTI_JWKS_URL: the platform's public keyset URL"):
        setting(MT_HUB_LOGIN="lti", **dict(platform, MT_HUB_LTI_JWKS_URL=""))
    with pytest.raises(SystemExit, match="MT_HUB_LOGIN: expected 'roster' or 'lti', got 'ldap'"):
        setting(MT_HUB_LOGIN="ldap")
    assert setting(MT_HUB_LOGIN="roster").JupyterHub.authenticator_class is RosterAuthenticator


def test_a_request_refused_for_a_full_disk_is_logged_naming_the_hubs_state_folder():
    import logging

    from sqlalchemy.exc import OperationalError

    state = Path("/srv/mt-hub 100%")  # a % in the folder must not break the log's format string
    log_filter = class_hub.DiskFullLog(state)

    def record(error):
        try:
            raise error
        except BaseException:
            return logging.LogRecord("tornado.application", logging.ERROR, __file__, 1,
                                     "Uncaught exception %s", ("POST /hub/login",), sys.exc_info())

    full = [record(OSError(28, "No space left on device")), record(OSError(122, "Disk quota exceeded")),
            record(OperationalError("INSERT", {}, Exception("database or disk is full")))]
    other = record(ValueError("no"))
    assert all(log_filter.filter(r) for r in (*full, other))  # every record is still logged
    for refused in full:
        assert refused.getMessage().startswith(f"Disk full: the hub's state folder {state} "), refused.getMessage()
        assert refused.getMessage().endswith("Uncaught exception POST /hub/login")
    assert other.getMessage() == "Uncaught exception POST /hub/login"
    assert not class_hub.is_disk_full(None) and not class_hub.is_disk_full(OSError(13, "Permission denied"))
