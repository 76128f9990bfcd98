"""mt_widgets/kernels/server_template.py as the hub runs it (root), without a hub: each fork is its
student before it runs anything, keeps nothing of another student's, and the template takes
requests from the hub's user only.

Two system users ``mtt-st-...`` are made and removed. The "server" each fork runs is a probe module
(written below) that reports what its process is and scans its own memory for the secrets planted
in every request's environment: a template that read requests itself would pass one student's
secret on to the next student's fork.
"""

from __future__ import annotations

import json
import os
import pwd
import secrets
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mt_widgets.kernels.server_template import ServerTemplate

from .course_support import REPO
from .hub_support import STUDENT_PYTHON

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="the server template forks as other users: run as root")

USERS = ("mtt-st-ann", "mtt-st-bob")
MARK = "MTTSECRET"

PROBE = '''
import json, os, re, sys, time


def main():
    out = sys.argv[1]
    report = {"resuid": os.getresuid(), "resgid": os.getresgid(), "groups": sorted(os.getgroups()),
              "cwd": os.getcwd(), "sid_is_self": os.getsid(0) == os.getpid()}
    try:
        os.setuid(0)
        report["became_root"] = True
    except PermissionError:
        report["became_root"] = False
    from mt_widgets.kernels import template
    from mt_widgets.kernels.provisioner import KernelTemplate
    caches = [f._cache._cache_path for f in template._cached_numba_functions("mt_widgets")]
    report["numba_caches"] = len(caches)
    report["numba_caches_elsewhere"] = [p for p in caches if not p.startswith(os.environ["NUMBA_CACHE_DIR"])]
    report["kernel_template_adopted"] = KernelTemplate.adopted()
    shared = KernelTemplate._shared
    for _ in range(100):
        if os.path.exists(shared.socket):
            break
        time.sleep(0.05)
    report["kernel_template_socket"] = shared.socket
    report["kernel_template_uid"] = os.stat(f"/proc/{shared.process.pid}").st_uid
    found = set()
    with open("/proc/self/maps") as maps, open("/proc/self/mem", "rb", 0) as mem:
        for line in maps:
            fields = line.split()
            if "r" not in fields[1] or (len(fields) > 5 and fields[5].startswith("[v")):
                continue
            start, end = (int(x, 16) for x in fields[0].split("-"))
            try:
                mem.seek(start)
                chunk = mem.read(end - start)
            except (OSError, ValueError, OverflowError):
                continue
            found.update(m.decode() for m in re.findall(rb"MTTSECRET[0-9a-f]{32}", chunk))
    report["secrets_in_memory"] = sorted(found)
    # The server's system facts come from the template, gathered once without running git
    # (a server's web app asks for them at every start).
    import subprocess
    import jupyter_server
    started = []
    popen = subprocess.Popen
    subprocess.Popen = lambda *args, **kwargs: started.append(args) or popen(*args, **kwargs)
    try:
        serverapp = sys.modules["jupyter_server.serverapp"]
        facts = serverapp.get_sys_info()
    finally:
        subprocess.Popen = popen
    replaced = serverapp.get_sys_info is not sys.modules["jupyter_server._sysinfo"].get_sys_info
    report["system_facts"] = [len(started), replaced, facts["jupyter_server_version"] == jupyter_server.__version__]
    # The installed kernel provisioners too: read from the packages' metadata once, in the template.
    factory = sys.modules["jupyter_client.provisioning.factory"]
    reads = []
    entry_points = factory.entry_points
    factory.entry_points = lambda *args, **kwargs: reads.append(args) or entry_points(*args, **kwargs)
    try:
        names = sorted(point.name for point in factory.KernelProvisionerFactory._get_all_provisioners())
    finally:
        factory.entry_points = entry_points
    report["provisioners"] = [len(reads), names]
    with open(out, "w") as handle:
        json.dump(report, handle)


# The template imports it first, as it imports a real server module: only run, it probes.
if __name__ == "__main__":
    main()
'''


@pytest.fixture(scope="module")
def users(tmp_path_factory):
    site = Path(f"/tmp/mtt-st-site-{secrets.token_hex(3)}")
    site.mkdir()
    # Explicit modes: the users must read the probe whatever the umask (CI's may be 077).
    os.chmod(site, 0o755)
    (site / "mtt_probe_server.py").write_text(PROBE)
    os.chmod(site / "mtt_probe_server.py", 0o644)
    made = {}
    try:
        for login in USERS:
            home = Path(f"/tmp/{login}-{secrets.token_hex(3)}")
            subprocess.run(["useradd", "--home-dir", str(home), "--no-create-home", "--shell", "/usr/sbin/nologin",
                            "--user-group", login], check=True, capture_output=True, timeout=60)
            account = pwd.getpwnam(login)
            for folder in (home, home / "runtime"):
                folder.mkdir(mode=0o700)
                os.chown(folder, account.pw_uid, account.pw_gid)
            made[login] = (account, home)
        yield site, made
    finally:
        for login in USERS:
            subprocess.run(["pkill", "-KILL", "-u", login], capture_output=True, timeout=60)
            subprocess.run(["userdel", login], capture_output=True, timeout=60)
        for _, home in made.values():
            shutil.rmtree(home, ignore_errors=True)
        shutil.rmtree(site, ignore_errors=True)


@pytest.fixture(scope="module")
def server_template(users):
    site, _ = users
    python = STUDENT_PYTHON if STUDENT_PYTHON.exists() else Path(sys.executable)
    template = ServerTemplate(python, servers=["mtt_probe_server"], kernels=[],
                              preload=["numpy", "mt_widgets", "jupyter_server.serverapp"],
                              env={"PATH": str(python.parent), "PYTHONPATH": f"{site}{os.pathsep}{REPO}",
                                   "PYTHONDONTWRITEBYTECODE": "1"})
    template.ensure_started()
    deadline = time.monotonic() + 120
    while not os.path.exists(template.socket):
        assert template.process.poll() is None, "the server template ended before it was ready"
        assert time.monotonic() < deadline, "the server template was not ready within 120 s"
        time.sleep(0.1)
    yield template
    template.stop()
    assert template.process.poll() is not None
    shutil.rmtree(template.folder, ignore_errors=True)


def _ask(template: ServerTemplate, request: dict) -> tuple[int | None, int | None, str]:
    """Send ``request`` as the hub does; (pid, exit status, error) once the fork has ended."""
    with socket.socket(socket.AF_UNIX) as conn:
        conn.settimeout(120)
        conn.connect(template.socket)
        conn.sendall(json.dumps(request).encode() + b"\n")
        lines = conn.makefile().read().splitlines()
    replies = [json.loads(line) for line in lines]
    pid = next((r["pid"] for r in replies if "pid" in r), None)
    status = next((r["status"] for r in replies if "status" in r), None)
    error = next((r["error"] for r in replies if "error" in r), "")
    return pid, status, error


def _request(template, account, home: Path, secret: str, **changes) -> dict:
    request = {
        "argv": [template.python, "-m", "mtt_probe_server", str(home / "report.json")],
        "env": {"HOME": str(home), "PATH": "/usr/bin", "SECRET_TOKEN": secret,
                "JUPYTER_RUNTIME_DIR": str(home / "runtime"), "NUMBA_CACHE_DIR": str(home / "numba"),
                "PYTHONPATH": template.env["PYTHONPATH"]},
        "cwd": str(home), "uid": account.pw_uid, "gid": account.pw_gid,
        "groups": os.getgrouplist(account.pw_name, account.pw_gid), "cgroup_procs": [],
    }
    request.update(changes)
    return request


def test_each_fork_is_its_student_and_holds_no_one_elses_secret(server_template, users):
    _, made = users
    planted = {}
    for login, (account, home) in made.items():
        planted[login] = MARK + secrets.token_hex(16)
        pid, status, error = _ask(server_template, _request(server_template, account, home, planted[login]))
        assert pid and status == 0 and not error, (login, pid, status, error)
        report = json.loads((home / "report.json").read_text())
        assert report["resuid"] == [account.pw_uid] * 3 and report["resgid"] == [account.pw_gid] * 3
        assert report["groups"] == sorted(set(os.getgrouplist(login, account.pw_gid)))
        assert report["became_root"] is False
        assert report["cwd"] == str(home) and report["sid_is_self"] is True
        # Its own secret is in its memory (the scan works); no one else's is.
        assert report["secrets_in_memory"] == [planted[login]], (login, report["secrets_in_memory"])
        # numba's compiled functions write to the student's own cache, never a folder shared with others.
        assert report["numba_caches"] > 0 and report["numba_caches_elsewhere"] == []
        # Their kernels come from a kernel template of their own, running as them, in their folder.
        assert report["kernel_template_adopted"] is True
        assert report["kernel_template_uid"] == account.pw_uid
        assert report["kernel_template_socket"].startswith(str(home / "runtime") + "/")
        # jupyter_server's system facts, as the template gathered them: no git run per server.
        assert report["system_facts"] == [0, True, True], report["system_facts"]
        assert report["provisioners"] == [0, ["local-provisioner"]], report["provisioners"]


def test_requests_that_would_run_as_root_or_another_module_run_nothing(server_template, users):
    _, made = users
    account, home = made[USERS[0]]
    (home / "report.json").unlink(missing_ok=True)
    for changes in ({"uid": 0}, {"gid": 0}, {"groups": [0, account.pw_gid]}, {"uid": "1000"},
                    {"argv": [server_template.python, "-m", "os", "x"]},
                    {"argv": ["/bin/sh", "-m", "mtt_probe_server", "x"]},
                    {"cgroup_procs": ["/etc/passwd"]}, {"cgroup_procs": ["/sys/fs/cgroup/../../etc/x/cgroup.procs"]}):
        pid, status, error = _ask(server_template, _request(server_template, account, home, "x", **changes))
        assert pid and status == 2, (changes, pid, status, error)
        assert not (home / "report.json").exists(), changes


def test_only_the_hubs_user_reaches_the_template(server_template, users):
    _, made = users
    account, _ = made[USERS[0]]
    # The socket's folder is root's alone: another user cannot even reach the socket.
    assert oct(os.stat(server_template.folder).st_mode & 0o777) == "0o700"
    probe = ("import socket, sys\ns = socket.socket(socket.AF_UNIX)\n"
             f"try:\n    s.connect({server_template.socket!r})\nexcept PermissionError:\n    sys.exit(7)\n")
    ran = subprocess.run(["/usr/bin/python3", "-c", probe], user=account.pw_uid, group=account.pw_gid,
                         extra_groups=[], capture_output=True, timeout=60)
    assert ran.returncode == 7, ran
    # Reached anyway (the folder opened up by mistake), the template refuses another user's request.
    os.chmod(server_template.folder, 0o755)
    os.chmod(server_template.socket, 0o666)
    try:
        probe = ("import socket\ns = socket.socket(socket.AF_UNIX)\n"
                 f"s.connect({server_template.socket!r})\nprint(s.makefile().read())\n")
        ran = subprocess.run(["/usr/bin/python3", "-c", probe], user=account.pw_uid, group=account.pw_gid,
                             extra_groups=[], capture_output=True, text=True, timeout=60)
    finally:
        os.chmod(server_template.folder, 0o700)
        os.chmod(server_template.socket, 0o600)
    assert "refused" in ran.stdout and "pid" not in ran.stdout, ran
