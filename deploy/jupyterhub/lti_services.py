"""The class hub as an LTI 1.3 tool: its key, the logins it gives platform users, and LTI Advantage's services.

What a course in a learning platform (Canvas, Moodle, ...) needs of the hub beyond the launch
(``lti_authenticator.py``):

- **The tool's key** (``ToolKey``): an RSA key pair, the private half in a PEM file readable by the
  hub's user only (0600, refused otherwise), the public half served as a JSON Web Key Set that the
  platform is given at registration; it signs the tool's OAuth 2 client assertions (1EdTech
  Security Framework 1.0, section 4.1).
- **Logins** (``login_for``): a platform user becomes the system user ``<prefix><16 letters>``,
  a hash of the platform's issuer and the user's ``sub`` (LTI's stable, opaque user id), never
  their display name, which a student may edit: two students cannot end up as one login, and a
  name change does not move anyone's files. The name and e-mail go to the roster's columns for
  the instructors' eyes (``mt_widgets/classroom/roster.py``, ``names.py``).
- **Roles** (``role_for``): the context roles Instructor and TeachingAssistant are the hub's
  ``instructor`` and ``ta`` (its admins); everyone else a ``student``. Institution roles (a
  site administrator) give no rights in a course.
- **Names and Role Provisioning Services 2.0** (``PlatformClient.members``, ``synced_roster``):
  the course's memberships, followed over ``Link: rel="next"`` pages, fill and update the roster.
- **Assignment and Grade Services 2.0** (``PlatformClient`` line items, results and scores,
  ``lti_grades.py``): one line item per nbgrader assignment (``resourceId`` ``nbgrader:<name>``),
  each student's total score posted only when the platform's result differs, so posting twice
  changes nothing.

Everything here runs with the hub's settings, as root (``class_admin.py lti-sync`` and
``lti-grades``): the tool's private key is root's alone.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import secrets
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import jwt
import requests
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa

from mt_widgets.classroom.roster import Roster, RosterEntry, login_problem

LTI = "https://purl.imsglobal.org/spec/lti/claim/"
NRPS_CLAIM = "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice"
AGS_CLAIM = "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint"
SCOPE_MEMBERSHIPS = "https://purl.imsglobal.org/spec/lti-nrps/scope/contextmembership.readonly"
SCOPE_LINEITEM = "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem"
SCOPE_RESULTS = "https://purl.imsglobal.org/spec/lti-ags/scope/result.readonly"
SCOPE_SCORE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
#: The scopes the tool asks a platform for at registration.
SCOPES = (SCOPE_MEMBERSHIPS, SCOPE_LINEITEM, SCOPE_RESULTS, SCOPE_SCORE)
ASSERTION_TYPE = "urn:ietf:params:oauth:client-assertion-type:jwt-bearer"
#: The default start of the logins of platform users (a roster login typed by hand never has it).
LOGIN_PREFIX = "lti-"
#: The line items the hub makes carry this tag, and ``resourceId`` ``nbgrader:<assignment>``.
LINE_ITEM_TAG = "mt-widgets"

_MEMBERSHIP = re.compile(r"^(?:http://purl\.imsglobal\.org/vocab/lis/v2/membership[#/])?(.+)$")


class LTIServiceError(RuntimeError):
    """A platform's service refused or answered what the specification does not allow."""


def login_for(issuer: str, sub: str, prefix: str = LOGIN_PREFIX) -> str:
    """The hub login (a system user name) of the platform user ``sub`` of the platform ``issuer``.

    Raises:
        ValueError: an empty issuer or sub, or a prefix that makes no valid login.
    """
    for name, value in (("issuer", issuer), ("sub", sub), ("prefix", prefix)):
        if not isinstance(value, str) or (not value and name != "prefix"):
            raise ValueError(f"{name}: expected a non-empty string, got {value!r}")
    digest = hashlib.sha256(f"{issuer}\n{sub}".encode()).digest()
    # 16 base32 letters are 80 bits: no two members of any class share one by chance.
    login = prefix + base64.b32encode(digest).decode().lower()[:16]
    problem = login_problem(login)
    if problem:
        raise ValueError(f"prefix: {prefix!r} makes no valid login ({problem})")
    return login


def role_for(roles) -> str:
    """The roster role ('instructor', 'ta' or 'student') of LTI context ``roles`` (full URIs or short names)."""
    if not isinstance(roles, (list, tuple)):
        raise ValueError(f"roles: expected a list of LTI role URIs, got {type(roles).__name__}")
    context = set()
    for role in roles:
        if isinstance(role, str) and "/institution/" not in role and "/system/" not in role:
            context.add(_MEMBERSHIP.match(role).group(1))
    if "Instructor#TeachingAssistant" in context or "TeachingAssistant" in context:
        return "ta"
    if "Instructor" in context or "Administrator" in context:
        return "instructor"
    return "student"


class ToolKey:
    """The tool's RSA key: the private half in a PEM file only its owner may read, the public half as a JWKS."""

    def __init__(self, private_key: rsa.RSAPrivateKey):
        self.private_key = private_key
        numbers = private_key.public_key().public_numbers()
        self._jwk = {"kty": "RSA", "e": _b64_int(numbers.e), "n": _b64_int(numbers.n)}
        # The key id is the key's RFC 7638 thumbprint: it changes when the key does.
        thumbprint = hashlib.sha256(json.dumps(self._jwk, separators=(",", ":"), sort_keys=True).encode()).digest()
        self.kid = base64.urlsafe_b64encode(thumbprint).rstrip(b"=").decode()

    @classmethod
    def load_or_create(cls, path) -> ToolKey:
        """The key in ``path``, made (mode 0600) when there is none.

        Raises:
            PermissionError: the file may be read by others than its owner, or is not the running user's.
        """
        path = Path(path)
        if not path.exists():
            key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
            pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                    serialization.NoEncryption())
            path.parent.mkdir(parents=True, exist_ok=True)
            descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(descriptor, "wb") as handle:
                handle.write(pem)
        status = path.stat()
        if status.st_mode & 0o077 or status.st_uid != os.geteuid():
            raise PermissionError(f"{path}: the tool's private key must be the hub user's alone (chmod 600, "
                                  f"owner uid {os.geteuid()}); it has mode {oct(status.st_mode & 0o777)} "
                                  f"and owner uid {status.st_uid}")
        return cls(serialization.load_pem_private_key(path.read_bytes(), password=None))

    def jwks(self) -> dict:
        """The public key set the platform is given (``public_jwk_url`` in Canvas, "Public keyset URL" in Moodle)."""
        return {"keys": [dict(self._jwk, alg="RS256", use="sig", kid=self.kid)]}

    def sign(self, claims: dict) -> str:
        return jwt.encode(claims, self.private_key, algorithm="RS256", headers={"kid": self.kid})


def _b64_int(number: int) -> str:
    return base64.urlsafe_b64encode(number.to_bytes((number.bit_length() + 7) // 8, "big")).rstrip(b"=").decode()


class PlatformClient:
    """The tool's calls to one platform's services, with OAuth 2 tokens got by a signed client assertion."""

    def __init__(self, client_id: str, token_url: str, key: ToolKey, session: requests.Session | None = None):
        if not client_id or not token_url:
            raise ValueError("client_id, token_url: expected the tool's client id and the platform's token URL")
        self.client_id, self.token_url, self.key = client_id, token_url, key
        self.session = session or requests.Session()
        self._tokens: dict[str, tuple[str, float]] = {}

    def token(self, scope: str) -> str:
        """An access token for ``scope`` (kept until a minute before it expires)."""
        kept = self._tokens.get(scope)
        if kept and kept[1] > time.time() + 60:
            return kept[0]
        now = int(time.time())
        assertion = self.key.sign({"iss": self.client_id, "sub": self.client_id, "aud": self.token_url,
                                   "iat": now, "exp": now + 300, "jti": secrets.token_urlsafe(16)})
        answer = self.session.post(self.token_url, timeout=30, data={
            "grant_type": "client_credentials", "client_assertion_type": ASSERTION_TYPE,
            "client_assertion": assertion, "scope": scope})
        if answer.status_code != 200:
            raise LTIServiceError(f"the platform's token endpoint {self.token_url} refused the tool "
                                  f"({answer.status_code}: {answer.text[:300]})")
        body = answer.json()
        self._tokens[scope] = (body["access_token"], time.time() + float(body.get("expires_in", 3600)))
        return body["access_token"]

    def _call(self, method: str, url: str, scope: str, accept: str, **kwargs) -> requests.Response:
        headers = {"Authorization": f"Bearer {self.token(scope)}", "Accept": accept, **kwargs.pop("headers", {})}
        answer = self.session.request(method, url, headers=headers, timeout=30, **kwargs)
        if answer.status_code >= 400:
            raise LTIServiceError(f"{method} {url}: {answer.status_code} {answer.text[:300]}")
        return answer

    def members(self, memberships_url: str) -> list[dict]:
        """Every member of the course (NRPS 2.0), over all pages."""
        members, url = [], memberships_url
        while url:
            answer = self._call("GET", url, SCOPE_MEMBERSHIPS,
                                "application/vnd.ims.lti-nrps.v2.membershipcontainer+json")
            members += answer.json().get("members", [])
            url = answer.links.get("next", {}).get("url")
        return members

    def line_items(self, lineitems_url: str, resource_id: str | None = None) -> list[dict]:
        params = {"resource_id": resource_id} if resource_id else {}
        return self._call("GET", lineitems_url, SCOPE_LINEITEM, "application/vnd.ims.lis.v2.lineitemcontainer+json",
                          params=params).json()

    def create_line_item(self, lineitems_url: str, label: str, score_maximum: float, resource_id: str) -> dict:
        item = {"label": label, "scoreMaximum": score_maximum, "resourceId": resource_id, "tag": LINE_ITEM_TAG}
        return self._call("POST", lineitems_url, SCOPE_LINEITEM, "application/vnd.ims.lis.v2.lineitem+json",
                          data=json.dumps(item), headers={"Content-Type": "application/vnd.ims.lis.v2.lineitem+json"}
                          ).json()

    def results(self, line_item_id: str) -> list[dict]:
        return self._call("GET", _beside(line_item_id, "results"), SCOPE_RESULTS,
                          "application/vnd.ims.lis.v2.resultcontainer+json").json()

    def post_score(self, line_item_id: str, score: dict) -> None:
        self._call("POST", _beside(line_item_id, "scores"), SCOPE_SCORE, "application/json",
                   data=json.dumps(score), headers={"Content-Type": "application/vnd.ims.lis.v1.score+json"})


def _beside(line_item_id: str, service: str) -> str:
    """The line item's ``/scores`` or ``/results`` URL (AGS 2.0: appended to its path, before a query)."""
    path, _, query = line_item_id.partition("?")
    return f"{path.rstrip('/')}/{service}" + (f"?{query}" if query else "")


# -- the roster from the platform ---------------------------------------------------------------------

@dataclass(frozen=True)
class RosterSync:
    """What a sync did: the new roster, who came and who went, and each platform login's ``sub``."""

    roster: Roster
    added: tuple[str, ...]
    dropped: tuple[str, ...]
    platform_ids: dict


def synced_roster(roster: Roster, members, issuer: str, prefix: str = LOGIN_PREFIX,
                  platform_ids: dict | None = None) -> RosterSync:
    """``roster`` brought up to the platform's ``members`` (NRPS member objects).

    Active members are added or updated (name, e-mail and role from the platform); a platform
    login whose member left the course, or is no longer Active, is dropped. Entries without
    ``prefix`` (typed into the roster by hand, as a local TA) are the instructor's and kept.
    """
    ids = dict(platform_ids or {})
    entries = {entry.login: entry for entry in roster.entries}
    active = {}
    for member in members:
        if member.get("status", "Active") != "Active" or not member.get("user_id"):
            continue
        login = login_for(issuer, member["user_id"], prefix)
        active[login] = RosterEntry(login, platform_name(member.get("name")), platform_email(member.get("email")),
                                    role_for(member.get("roles", [])))
        ids[login] = member["user_id"]
    added = tuple(login for login in active if login not in entries)
    dropped = tuple(login for login in entries if login.startswith(prefix) and login not in active)
    kept = [active.get(entry.login, entry) for entry in roster.entries if entry.login not in dropped]
    new = Roster(tuple(kept) + tuple(active[login] for login in added))
    return RosterSync(new, added, dropped, ids)


def platform_name(text) -> str:
    """A platform's display name as a roster field: one line, no surrounding spaces or control characters."""
    return " ".join("".join(c if ord(c) >= 32 and ord(c) != 127 else " " for c in str(text or "")).split())


def platform_email(text) -> str:
    email = platform_name(text)
    return email if re.fullmatch(r"[^@\s,;<>]+@[^@\s,;<>]+\.[^@\s,;<>]+", email) else ""


def read_platform_ids(path) -> dict:
    """{login: the platform's sub} kept by the launch and the sync (JSON, 0600); {} when none yet."""
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}


def write_private_json(path, data) -> None:
    """``data`` as JSON in ``path``, replaced atomically, readable by its owner only."""
    path = Path(path)
    descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        os.fchmod(descriptor, 0o600)
        with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
            json.dump(data, handle, indent=1, sort_keys=True)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise
