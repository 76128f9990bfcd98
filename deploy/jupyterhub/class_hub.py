"""What the class hub does as root so that students are isolated: accounts, folders, limits.

Used by ``jupyterhub_config.py`` (the spawner and its hooks) and by ``class_admin.py`` (the
instructor's command); one place for each mechanism:

- **System users.** Every roster login is a system user of its own (``useradd``, its own
  group, no login shell, the comment ``MARKER`` so the hub only ever changes or removes
  accounts it made), with a private home (0700). Instructors and TAs are also in the
  instructors' group. A login that already exists as a system user the hub did not make is
  refused: a student never gets someone else's account.
- **The class folder** (``mt_widgets/classroom/progress.py``): owned by root and the
  instructors' group, mode 3773 (setgid, sticky; others may create files and enter, not list).
  Each student's ``<pseudonym>.jsonl`` and ``.locks/<pseudonym>.lock`` are made by the hub before
  their server starts, owned by the student and the instructors' group, mode 0640: the student
  appends to their own file, the instructors read every file, no student reads or alters a
  classmate's, nor takes a classmate's file name first. Students' servers run with umask 027
  (student-config/jupyter_server_config.py), so nothing else they write there is readable by
  classmates either.
- **The course folder** (``source/``, ``gradebook.db``, ``autograded/``, ``feedback/``): root and
  the instructors' group, 2770; nothing in it is readable by others.
- **Limits** (``CgroupLimits``): on a machine without systemd, cgroup v1 memory and cpu groups
  ``<the hub's own group>/mt-hub/<login>``, one per student, that the server (and so each of its
  kernels) joins before it drops root; nested under the hub's own group, so a hub started
  inside a container or a slice stays within that one's limits too. On a systemd host,
  jupyterhub-systemdspawner does the same with systemd's own units (see README.md).
- **The installation** must be readable and traversable by every student (``installation_problems``):
  the hub refuses to start a class it would only half serve.
"""

from __future__ import annotations

import errno
import grp
import logging
import os
import pwd
import re
import shutil
import signal
import stat
import subprocess
import time
from pathlib import Path

from mt_widgets.classroom.progress import LOCK_FOLDER, create_class_folder, pseudonym, read_class_meta

#: The class's limits and culling unless the hub's environment says otherwise; the Zero to
#: JupyterHub values (z2jh/values.yaml) carry the same (tests/course/test_hub_config.py checks).
DEFAULT_MEM_LIMIT = "1G"
DEFAULT_CPU_LIMIT = 1.0
DEFAULT_CULL_IDLE_S = 3600
#: The comment (GECOS) of every account this hub creates: it changes or removes no other.
MARKER = "mt-widgets class hub"
#: Class folder mode: setgid (files keep the instructors' group), sticky (nobody removes another's
#: file), owner and group rwx, others may create and enter but not list.
CLASS_FOLDER_MODE = 0o3773
PROGRESS_FILE_MODE = 0o640
COURSE_FOLDER_MODE = 0o2770
NOLOGIN = next((shell for shell in ("/usr/sbin/nologin", "/sbin/nologin", "/bin/false") if os.path.exists(shell)),
               "/bin/false")


class ClassHubError(RuntimeError):
    """Something the class hub cannot set up safely, with what to do about it."""


def _run(*command: str) -> None:
    result = subprocess.run(command, capture_output=True, text=True, timeout=60)
    if result.returncode != 0:
        raise ClassHubError(f"{' '.join(command)} failed ({result.returncode}): {result.stderr.strip()}")


# -- accounts -----------------------------------------------------------------------------------------
def ensure_group(name: str) -> int:
    """The id of group ``name``, created when missing."""
    try:
        return grp.getgrnam(name).gr_gid
    except KeyError:
        _run("groupadd", name)
        return grp.getgrnam(name).gr_gid


def is_hub_account(login: str) -> bool:
    """True when ``login`` is a system user this hub made."""
    try:
        return pwd.getpwnam(login).pw_gecos == MARKER
    except KeyError:
        return False


def ensure_system_user(login: str, home: Path, instructors_group: str, admin: bool) -> pwd.struct_passwd:
    """``login``'s system user with its private home (0700), created when missing.

    Args:
        login: a roster login (already checked safe by mt_widgets/classroom/roster.py).
        home: their home folder.
        instructors_group: the instructors' group, which instructors and TAs join.
        admin: True for instructors and TAs; False for students (who are taken out of the
            instructors' group, should they have been TAs before).

    Raises:
        ClassHubError: the login is a system user the hub did not make, or useradd failed.
    """
    home = Path(home)
    try:
        user = pwd.getpwnam(login)
    except KeyError:
        _run("useradd", "--home-dir", str(home), "--no-create-home", "--shell", NOLOGIN, "--user-group",
             "--comment", MARKER, login)
        user = pwd.getpwnam(login)
    if user.pw_gecos != MARKER:
        raise ClassHubError(f"system user {login!r} exists and was not made by the class hub (comment "
                            f"{user.pw_gecos!r}, not {MARKER!r}): rename the roster login, or remove that account")
    if user.pw_uid == 0:
        raise ClassHubError(f"system user {login!r} has uid 0: the hub never runs a student as root")
    if Path(user.pw_dir) != home:
        _run("usermod", "--home", str(home), login)
        user = pwd.getpwnam(login)
    home.mkdir(parents=True, exist_ok=True)
    os.chown(home, user.pw_uid, user.pw_gid)
    os.chmod(home, 0o700)
    members = grp.getgrnam(instructors_group).gr_mem
    if admin and login not in members:
        _run("usermod", "--append", "--groups", instructors_group, login)
    elif not admin and login in members:
        _run("gpasswd", "--delete", login, instructors_group)
    return user


def remove_system_user(login: str, remove_home: bool = False) -> bool:
    """Removes ``login``'s system user if the hub made it (their home stays unless ``remove_home``).

    Returns:
        True when an account was removed.
    """
    if not is_hub_account(login):
        return False
    home = pwd.getpwnam(login).pw_dir
    _run("userdel", login)
    if remove_home and home and Path(home).is_dir():
        shutil.rmtree(home)
    return True


# -- folders ----------------------------------------------------------------------------------------
def secure_class_folder(folder: Path, instructors_gid: int) -> dict:
    """Makes ``folder`` a class folder only instructors can list (see the module docstring)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    meta = create_class_folder(folder)
    for path in (folder, folder / LOCK_FOLDER):
        path.mkdir(exist_ok=True)
        os.chown(path, 0, instructors_gid)
        os.chmod(path, CLASS_FOLDER_MODE)
    os.chmod(folder / "class.json", 0o644)  # the salt: every student's recorder reads it
    return meta


def ensure_progress_files(folder: Path, login: str, instructors_gid: int, log=None) -> Path:
    """``login``'s progress file and lock file, theirs and the instructors' group's, mode 0640."""
    folder = Path(folder)
    name = pseudonym(login, read_class_meta(folder)["salt"])
    user = pwd.getpwnam(login)
    made = []
    for path in (folder / f"{name}.jsonl", folder / LOCK_FOLDER / f"{name}.lock"):
        descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_NOFOLLOW, PROGRESS_FILE_MODE)
        try:
            info = os.fstat(descriptor)
            if info.st_uid not in (0, user.pw_uid) and log is not None:
                log.warning("%s was created by uid %d before %s's first start; it is now theirs",
                            path, info.st_uid, login)
            os.fchown(descriptor, user.pw_uid, instructors_gid)
            os.fchmod(descriptor, PROGRESS_FILE_MODE)
        finally:
            os.close(descriptor)
        made.append(path)
    return made[0]


def secure_course_folder(folder: Path, instructors_gid: int) -> None:
    """The instructor's course folder: root and the instructors' group only (2770, nothing for others)."""
    folder = Path(folder)
    os.chown(folder, 0, instructors_gid)
    os.chmod(folder, COURSE_FOLDER_MODE)
    for path in folder.rglob("*"):
        if path.is_symlink():
            continue
        mode = stat.S_IMODE(path.lstat().st_mode)
        os.chmod(path, mode & ~0o007)


def is_disk_full(error: BaseException | None) -> bool:
    """Whether ``error`` is a write refused for want of space: an OSError of a full disk or quota, or
    SQLite's "database or disk is full" (SQLAlchemy's OperationalError carries it in its text)."""
    if error is None:
        return False
    if isinstance(error, OSError) and error.errno in (errno.ENOSPC, errno.EDQUOT):
        return True
    return "database or disk is full" in str(error)


class DiskFullLog(logging.Filter):
    """Puts one line in words before the traceback of a request that failed for a full disk: which
    folder is full and what to do (a log filter on tornado's ``tornado.application``, where an
    uncaught error in a request is logged). Every record passes."""

    def __init__(self, state: Path):
        super().__init__()
        self.state = Path(state)

    def filter(self, record: logging.LogRecord) -> bool:
        if record.exc_info and is_disk_full(record.exc_info[1]):
            folder = str(self.state).replace("%", "%%")  # the message is a format string
            record.msg = (f"Disk full: the hub's state folder {folder} (its database, the password hashes) "
                          "has no space left: the request was refused and nothing of it was stored; free space "
                          "there, and the hub goes on without a restart (docs/guide/faults.md). " + str(record.msg))
        return True


def installation_problems(paths) -> list[str]:
    """What stops students (who are neither owner nor group) from using the installation at ``paths``.

    Every folder from / down to each path must be searchable by others (o+x), and each path
    readable (o+r). Returns one sentence per problem, with the chmod that fixes it.
    """
    problems = []
    for path in paths:
        path = Path(path).resolve()
        for folder in [*reversed(path.parents), path] if path.is_dir() else reversed(path.parents):
            if not stat.S_IMODE(folder.stat().st_mode) & stat.S_IXOTH:
                problems.append(f"students cannot enter {folder} (needed for {path}): chmod o+x {folder}")
        mode = stat.S_IMODE(path.stat().st_mode)
        if not mode & stat.S_IROTH:
            problems.append(f"students cannot read {path}: chmod o+r {path}")
        if path.is_file() and mode & stat.S_IXUSR and not mode & stat.S_IXOTH:
            problems.append(f"students cannot run {path}: chmod o+x {path}")
    return sorted(set(problems))


# -- limits -----------------------------------------------------------------------------------------
def _own_cgroup(controller: str) -> str:
    """The hub's own cgroup v1 path for ``controller`` (from /proc/self/cgroup)."""
    for line in Path("/proc/self/cgroup").read_text().splitlines():
        _, controllers, path = line.split(":", 2)
        if controller in controllers.split(","):
            return path
    raise ClassHubError(f"no cgroup v1 '{controller}' controller in /proc/self/cgroup")


_SIZE = re.compile(r"(\d+(?:\.\d+)?)\s*([KMGT]?)i?B?", re.IGNORECASE)


def parse_bytes(text: str) -> int:
    """'512M', '1G', '1.5GiB' or a plain byte count as bytes."""
    match = _SIZE.fullmatch(str(text).strip())
    if not match:
        raise ValueError(f"memory limit: expected bytes or a size like '512M' or '1G', got {text!r}")
    return int(float(match[1]) * 1024 ** " KMGT".index((match[2] or " ").upper()))


class CgroupLimits:
    """Memory and CPU limits per student in cgroup v1 groups ``<hub's group>/<parent>/<login>``.

    Args:
        memory_bytes: the student's server and kernels together (swap included where the
            kernel accounts for it); the kernel's OOM killer ends the largest process in the
            group, the runaway kernel, and nothing of any other student.
        cpus: CPU time per period (1.0 = one core), by the CFS quota.
        parent: the folder grouping the class's groups.
        root: where the cgroup v1 hierarchies are mounted.
    """

    CONTROLLERS = ("memory", "cpu")

    def __init__(self, memory_bytes: int, cpus: float, parent: str = "mt-hub", root: str = "/sys/fs/cgroup"):
        if memory_bytes < 64 * 2**20:
            raise ValueError(f"memory_bytes: expected at least 64 MiB, got {memory_bytes}")
        if cpus <= 0:
            raise ValueError(f"cpus: expected a positive share of a core, got {cpus}")
        self.memory_bytes, self.cpus, self.parent, self.root = int(memory_bytes), float(cpus), parent, Path(root)

    def problem(self) -> str | None:
        """Why limits cannot be enforced here, or None."""
        for controller in self.CONTROLLERS:
            mount = self.root / controller
            if not (mount / "cgroup.procs").exists():
                return f"no cgroup v1 {controller} hierarchy at {mount}"
            try:
                base = self.base(controller)
                base.mkdir(parents=True, exist_ok=True)
            except (OSError, ClassHubError) as error:
                return f"cannot create {controller} groups: {error}"
        return None

    def base(self, controller: str) -> Path:
        return self.root / controller / _own_cgroup(controller).lstrip("/") / self.parent

    def groups(self, login: str) -> list[Path]:
        return [self.base(controller) / login for controller in self.CONTROLLERS]

    def create(self, login: str) -> list[Path]:
        """Creates (or updates) ``login``'s groups with the limits."""
        memory, cpu = self.groups(login)
        for group in (memory, cpu):
            group.mkdir(parents=True, exist_ok=True)
        memsw = memory / "memory.memsw.limit_in_bytes"
        # memsw must stay >= the memory limit: raise it first when the limit grows, after when it shrinks.
        current = int((memory / "memory.limit_in_bytes").read_text())
        order = ["memory.limit_in_bytes", "memory.memsw.limit_in_bytes"]
        if self.memory_bytes > current:
            order.reverse()
        for name in order:
            if name == "memory.memsw.limit_in_bytes" and not memsw.exists():
                continue
            (memory / name).write_text(str(self.memory_bytes))
        period = int((cpu / "cpu.cfs_period_us").read_text())
        (cpu / "cpu.cfs_quota_us").write_text(str(int(self.cpus * period)))
        return [memory, cpu]

    def procs_files(self, login: str) -> list[str]:
        """The files a process writes its pid to (as root) to join ``login``'s groups."""
        return [str(group / "cgroup.procs") for group in self.groups(login)]

    def join_function(self, login: str):
        """A function for a child process (before exec, still root) that moves it into ``login``'s groups."""
        files = self.procs_files(login)

        def join():
            for path in files:
                with open(path, "w") as handle:
                    handle.write(str(os.getpid()))

        return join

    def processes(self, login: str) -> list[int]:
        pids = set()
        for group in self.groups(login):
            try:
                pids.update(int(p) for p in (group / "cgroup.procs").read_text().split())
            except FileNotFoundError:
                continue
        return sorted(pids)

    def remove(self, login: str) -> None:
        """Ends whatever is left in ``login``'s groups (a kernel outliving its server) and removes them."""
        for pid in self.processes(login):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        for group in self.groups(login):
            for _ in range(50):
                try:
                    group.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError:  # EBUSY while the killed processes are being reaped
                    time.sleep(0.1)

    def remove_parent(self) -> None:
        for controller in self.CONTROLLERS:
            try:
                self.base(controller).rmdir()
            except OSError:
                pass
