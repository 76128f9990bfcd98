"""The class hub's authenticator: exactly the people on the roster, each with a password of their own.

Why our own (on JupyterHub's ``Authenticator`` API) rather than FirstUseAuthenticator or
NativeAuthenticator: the class list is the instructor's roster file
(``mt_widgets/classroom/roster.py``), and the rules a class needs are few and must hold
together:

- a login that is not on the roster is refused, whatever the password (the roster is re-read
  when the file changes, so ``class_admin.py add``/``remove`` act without a restart);
- a student sets their password at their first login (at least ``min_password_length``
  characters); from then on nobody else can claim the login;
- instructors and TAs (the roster's admins) never claim a password at login: theirs is set
  beforehand with ``class_admin.py set-password``; until then every password is refused;
- after ``max_failures`` wrong passwords in a row a login is locked for ``lockout_seconds``
  (doubling on each further lock), and every failure costs ``failure_delay_seconds``, so
  guessing is slow; the lock is per login and in the hub's memory (a restart clears it);
- passwords are stored as scrypt hashes (salted, standard library) in a JSON file readable by
  the hub's user only (0600), written atomically under a file lock, so ``class_admin.py`` and
  the hub can both change it.

FirstUseAuthenticator lets an admin's login be claimed by whoever comes first; NativeAuthenticator
keeps its own sign-up list beside the roster. With an institution's single sign-on (OAuth, LTI,
PAM) a class would use that instead, with ``allowed_users`` from the roster.
"""

from __future__ import annotations

import asyncio
import base64
import fcntl
import hashlib
import hmac
import json
import os
import secrets
import tempfile
import threading
import time
from pathlib import Path

from jupyterhub.auth import Authenticator
from traitlets import Float, Integer, Unicode

from mt_widgets.classroom.roster import Roster, read_roster

#: scrypt's cost (2**14, r=8: 16 MiB and ~50 ms a hash on this machine's cores, the
#: interactive-login figure of the scrypt paper).
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**14, 8, 1


def hash_password(password: str) -> str:
    """A salted scrypt hash of ``password``, as 'scrypt$n$r$p$salt$hash' (base64)."""
    if not isinstance(password, str) or not password:
        raise ValueError("password: expected a non-empty string")
    salt = secrets.token_bytes(16)
    digest = hashlib.scrypt(password.encode(), salt=salt, n=SCRYPT_N, r=SCRYPT_R, p=SCRYPT_P, dklen=32)
    return "$".join(["scrypt", str(SCRYPT_N), str(SCRYPT_R), str(SCRYPT_P),
                     base64.b64encode(salt).decode(), base64.b64encode(digest).decode()])


def verify_password(password: str, stored: str) -> bool:
    """True when ``password`` is the one ``stored`` (from ``hash_password``) was made of."""
    try:
        kind, n, r, p, salt, digest = stored.split("$")
        if kind != "scrypt":
            return False
        expected = base64.b64decode(digest)
        actual = hashlib.scrypt(password.encode(), salt=base64.b64decode(salt), n=int(n), r=int(r), p=int(p),
                                dklen=len(expected))
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(actual, expected)


class PasswordStore:
    """The hashed passwords of a class: {login: hash} in a JSON file (0600), changed under a lock."""

    def __init__(self, path):
        self.path = Path(path)
        self._threads = threading.Lock()

    def _locked(self):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        lock = open(self.path.with_name(self.path.name + ".lock"), "a")
        fcntl.flock(lock, fcntl.LOCK_EX)
        return lock

    def read(self) -> dict[str, str]:
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return {}
        if not isinstance(data, dict):
            raise ValueError(f"{self.path}: expected an object of login -> hash, got {type(data).__name__}")
        return data

    def get(self, login: str) -> str | None:
        return self.read().get(login)

    def _write(self, data: dict[str, str]) -> None:
        descriptor, temporary = tempfile.mkstemp(prefix=f".{self.path.name}.", dir=self.path.parent)
        try:
            os.fchmod(descriptor, 0o600)
            with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
                json.dump(data, handle, indent=1, sort_keys=True)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(temporary, self.path)
        except BaseException:
            if os.path.exists(temporary):
                os.unlink(temporary)
            raise

    def set(self, login: str, password_hash: str | None, only_if_unset: bool = False) -> bool:
        """Stores (or with None removes) ``login``'s hash; with ``only_if_unset``, only when it has none.

        Returns:
            True when the store was changed.
        """
        with self._threads:
            lock = self._locked()
            try:
                data = self.read()
                if only_if_unset and login in data:
                    return False
                if password_hash is None:
                    if login not in data:
                        return False
                    del data[login]
                else:
                    data[login] = password_hash
                self._write(data)
                return True
            finally:
                lock.close()


class RosterAuthenticator(Authenticator):
    """Admits the roster's people with their own passwords (see the module's docstring)."""

    roster_path = Unicode(help="The class roster (CSV, mt_widgets/classroom/roster.py).").tag(config=True)
    password_file = Unicode(help="Where the password hashes are kept (JSON, 0600).").tag(config=True)
    min_password_length = Integer(10, help="The shortest password a student may set.").tag(config=True)
    max_failures = Integer(5, help="Wrong passwords in a row before a login is locked.").tag(config=True)
    lockout_seconds = Float(60.0, help="How long the first lock lasts; each further lock doubles it.").tag(
        config=True)
    failure_delay_seconds = Float(1.0, help="How long every refused login waits before its answer.").tag(
        config=True)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._roster: Roster | None = None
        self._roster_stamp = None
        self._failures: dict[str, int] = {}
        self._locks: dict[str, tuple[float, int]] = {}  # login -> (locked until, how many locks so far)

    @property
    def store(self) -> PasswordStore:
        return PasswordStore(self.password_file)

    @property
    def roster(self) -> Roster:
        """The roster file's current content (re-read when it changes; a bad new file keeps the last good one)."""
        stat = os.stat(self.roster_path)
        stamp = (stat.st_mtime_ns, stat.st_size, stat.st_ino)
        if stamp != self._roster_stamp:
            try:
                roster = read_roster(self.roster_path)
            except ValueError as error:
                if self._roster is None:
                    raise
                self.log.error("Roster %s refused, keeping the last good one: %s", self.roster_path, error)
            else:
                self._roster, self._roster_stamp = roster, stamp
        return self._roster

    def check_allowed(self, username, authentication=None):
        return username in self.roster

    async def refresh_user(self, user, handler=None):
        # A student removed from the roster mid-term loses their session at the next refresh.
        return user.name in self.roster

    async def authenticate(self, handler, data):
        login = self.normalize_username((data or {}).get("username") or "")
        password = (data or {}).get("password") or ""
        refusal = await self._check(login, password)
        if refusal is None:
            self._failures.pop(login, None)
            return {"name": login, "admin": self.roster.entry(login).is_admin}
        self.log.warning("Login refused for %r: %s", login, refusal)
        await asyncio.sleep(self.failure_delay_seconds)
        return None

    async def _check(self, login: str, password: str) -> str | None:
        """None when ``login`` may come in with ``password``, else the reason (for the hub's log only)."""
        if login not in self.roster:
            return "not on the roster"
        until, _ = self._locks.get(login, (0.0, 0))
        if time.monotonic() < until:
            return f"locked for {until - time.monotonic():.0f} s more after repeated wrong passwords"
        stored = self.store.get(login)
        if stored is None:
            if self.roster.entry(login).is_admin:
                return "an admin's password is set with class_admin.py set-password, never at login"
            if len(password) < self.min_password_length:
                return f"a first password must have at least {self.min_password_length} characters"
            password_hash = await asyncio.to_thread(hash_password, password)
            if self.store.set(login, password_hash, only_if_unset=True):
                self.log.info("%s set their password at their first login", login)
                return None
            stored = self.store.get(login)  # someone else's first login won the race: check against theirs
        if await asyncio.to_thread(verify_password, password, stored):
            return None
        failures = self._failures.get(login, 0) + 1
        self._failures[login] = failures
        if failures >= self.max_failures:
            _, locks = self._locks.get(login, (0.0, 0))
            self._locks[login] = (time.monotonic() + self.lockout_seconds * 2**locks, locks + 1)
            self._failures[login] = 0
            return f"wrong password ({failures} in a row: locked)"
        return f"wrong password ({failures} in a row)"
