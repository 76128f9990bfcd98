"""The class hub's login from a learning platform: LTI 1.3 launches (``MT_HUB_LOGIN=lti``).

Built on jupyterhub-ltiauthenticator's ``LTI13Authenticator`` (its OpenID Connect login
initiation, its state and nonce cookies, its required-claims validator), with what a class needs
on top:

- **Who**: the login is ``lti_services.login_for(issuer, sub)``, from the platform's stable user
  id, never a display name or e-mail a student can edit (ltiauthenticator's default is the
  e-mail claim); the person is written to the roster (name and e-mail for instructors only) so
  the hub makes the same isolated system user, limits and progress files as for a roster login.
  Instructor and TeachingAssistant launches are the hub's admins (the instructors' group).
- **Which platform, which deployment**: only the configured issuer's tokens, signed by a key of
  its key set, for this tool's client id and one of the configured deployment ids (the library
  leaves the deployment unchecked).
- **Replays**: the nonce must be the one this browser's login initiation made (the library's
  cookie), and each nonce is accepted once (kept until its token expires).
- **Refusals**: every refused launch gets a page saying what was wrong and what to do, and a log
  line with the reason and the claimed issuer and deployment; no token, nonce or launch is
  logged (the hub's request log hides the nonce and login hints of the redirect to the platform;
  the library's own debug lines print the whole launch: the hub logs at INFO).

``LaunchVerifier`` is the check, usable without a hub (tests/course/test_lti.py).
"""

from __future__ import annotations

import asyncio
import fcntl
import json
import threading
import time
from pathlib import Path

import jupyterhub.log
import jwt
from jupyterhub.handlers import BaseHandler
from jupyterhub.utils import url_path_join
from lti_services import (
    AGS_CLAIM,
    LOGIN_PREFIX,
    LTI,
    NRPS_CLAIM,
    SCOPES,
    ToolKey,
    login_for,
    platform_email,
    platform_name,
    read_platform_ids,
    role_for,
    write_private_json,
)
from ltiauthenticator.lti13.auth import LTI13Authenticator
from ltiauthenticator.lti13.error import MissingRequiredArgumentError, ValidationError
from ltiauthenticator.lti13.handlers import LTI13CallbackHandler, LTI13ConfigHandler, LTI13LoginInitHandler, get_nonce
from ltiauthenticator.lti13.validator import LTI13LaunchValidator
from tornado.web import HTTPError
from traitlets import Integer, Set, Unicode

from mt_widgets.classroom.roster import RosterEntry, read_roster, write_roster


class VerifiedLaunch(dict):
    """A launch's claims, as ``LaunchVerifier`` returned them to the launch handler.

    JupyterHub's own ``/hub/login`` still answers a POST, and hands its form fields to the
    authenticator as a dict: ``authenticate`` takes nothing but this type, which only the launch
    handler makes, so no form can sign anyone in as a platform user.
    """


class LaunchRefused(Exception):
    """A launch the hub refuses; ``reason`` says why in words a student or instructor can act on."""

    def __init__(self, reason: str, issuer: str = "", deployment: str = ""):
        super().__init__(reason)
        self.reason, self.issuer, self.deployment = reason, issuer, deployment


class LaunchVerifier:
    """Checks a launch's id_token: the platform, its signature, its time, the tool, the deployment, the nonce.

    Args:
        issuer: the platform's issuer (its URL, as its registration page gives it).
        client_ids: the tool's client ids at that platform.
        deployment_ids: the deployments of the tool this hub serves.
        jwks_url: the platform's public key set.
        max_age_s: how old (``iat``) a token may be; its own ``exp`` is checked too.
    """

    def __init__(self, issuer: str, client_ids, deployment_ids, jwks_url: str, max_age_s: int = 600):
        for name, value in (("issuer", issuer), ("jwks_url", jwks_url)):
            if not isinstance(value, str) or not value:
                raise ValueError(f"{name}: expected the platform's {name} (a URL), got {value!r}")
        if not client_ids or not deployment_ids:
            raise ValueError("client_ids, deployment_ids: expected at least one of each "
                             f"(got {sorted(client_ids)!r} and {sorted(deployment_ids)!r})")
        self.issuer, self.client_ids, self.deployment_ids = issuer, set(client_ids), set(deployment_ids)
        self.keys = jwt.PyJWKClient(jwks_url, cache_keys=True, lifespan=300)
        self.validator = LTI13LaunchValidator(max_age=max_age_s)
        self._nonces: dict[str, float] = {}  # nonce -> until when it is kept
        self._lock = threading.Lock()

    def verify(self, id_token: str, expected_nonce: str | None) -> dict:
        """The launch's claims; LaunchRefused naming what is wrong. ``expected_nonce`` is the nonce this
        browser's login initiation sent the platform (None when the browser brought no such cookie)."""
        try:
            claimed = jwt.decode(id_token, options={"verify_signature": False})
        except jwt.PyJWTError:
            raise LaunchRefused("the launch's token is not a signed token") from None
        issuer, deployment = str(claimed.get("iss", "")), str(claimed.get(LTI + "deployment_id", ""))

        def refuse(reason: str):
            return LaunchRefused(reason, issuer, deployment)

        if issuer != self.issuer:
            raise refuse(f"the launch comes from another platform ({issuer or 'none named'}), not this "
                         f"course's ({self.issuer})")
        try:
            key = self.keys.get_signing_key_from_jwt(id_token).key
        except jwt.PyJWTError:
            raise refuse("the launch is signed with a key that is not in the platform's key set") from None
        try:
            claims = jwt.decode(id_token, key, algorithms=["RS256"], audience=sorted(self.client_ids),
                                issuer=self.issuer, options={"require": ["exp", "iat", "sub"]})
        except jwt.ExpiredSignatureError:
            raise refuse("the launch has expired (open the tool again from your course page)") from None
        except jwt.InvalidSignatureError:
            raise refuse("the launch's signature is wrong") from None
        except jwt.InvalidAudienceError:
            raise refuse("the launch is meant for another tool (its audience is not this hub's client id)") from None
        except jwt.PyJWTError as error:
            raise refuse(f"the launch's token is invalid ({error})") from None
        try:
            self.validator.validate_id_token(claims)
            self.validator.validate_azp_claim(claims, self.client_ids)
        except MissingRequiredArgumentError as error:
            if "nonce" in str(error):
                raise refuse("the launch has no nonce") from None
            raise refuse(f"the launch lacks what LTI 1.3 requires ({error})") from None
        except ValidationError as error:
            raise refuse(f"the launch is not a valid LTI 1.3 launch ({error})") from None
        if deployment not in self.deployment_ids:
            raise refuse(f"the launch comes from another deployment of the tool ({deployment}) than this "
                         "course's")
        if expected_nonce is None or claims["nonce"] != expected_nonce:
            raise refuse("the launch's nonce is not the one this browser's login started (a replayed launch, "
                         "or the browser dropped the hub's cookie)")
        with self._lock:
            now = time.time()
            self._nonces = {nonce: until for nonce, until in self._nonces.items() if until > now}
            if claims["nonce"] in self._nonces:
                raise refuse("the launch was used before (a replayed launch)")
            self._nonces[claims["nonce"]] = max(float(claims["exp"]), now) + 60
        return claims


def _refuse(handler, refusal: LaunchRefused) -> HTTPError:
    """The log line and the page of a refused launch (the token itself is never logged)."""
    handler.log.warning("LTI launch refused: %s (issuer %s, deployment %s)", refusal.reason,
                        refusal.issuer or "-", refusal.deployment or "-")
    return HTTPError(403, f"This launch was refused: {refusal.reason}. Open mt-widgets again from your "
                          "course page; if this happens again, tell your instructor.")


class ClassLTILoginInitHandler(LTI13LoginInitHandler):
    """The platform's login initiation: only from this course's platform and tool, else a clear page."""

    def post(self):
        issuer, client_id = self.get_argument("iss", ""), self.get_argument("client_id", "")
        if not issuer or not self.get_argument("login_hint", ""):
            raise HTTPError(400, "This hub has no password login: open mt-widgets from your course page in the "
                                 "learning platform.")
        if issuer != self.authenticator.issuer:
            raise _refuse(self, LaunchRefused(f"the launch comes from another platform ({issuer}), not this "
                                              f"course's ({self.authenticator.issuer})", issuer))
        if client_id and client_id not in self.authenticator.client_id:
            raise _refuse(self, LaunchRefused("the launch is meant for another tool (its client id is not this "
                                              "hub's)", issuer))
        if not client_id and len(self.authenticator.client_id) == 1:
            # LTI makes client_id optional here; the authentication request needs it.
            self.request.arguments["client_id"] = [next(iter(self.authenticator.client_id)).encode()]
        return super().post()

    get = post


class ClassLTICallbackHandler(LTI13CallbackHandler):
    """The launch: verified by the authenticator's ``LaunchVerifier``; a refusal is a page and a log line."""

    async def post(self):
        try:
            id_token, expected_nonce = self._launch()
            # In a thread: the platform's key set may have to be fetched, which must not hold up the hub.
            claims = await asyncio.to_thread(self.authenticator.verifier.verify, id_token, expected_nonce)
        except LaunchRefused as refusal:
            raise _refuse(self, refusal) from None
        user = await self.login_user(VerifiedLaunch(claims))
        if user is None:
            raise HTTPError(403, "This launch was refused.")
        await self.redirect_to_next_url(user)

    def _launch(self) -> tuple[str, str | None]:
        """The launch's id_token and the nonce this browser's login initiation sent (from its cookies)."""
        id_token, state = self.get_body_argument("id_token", ""), self.get_body_argument("state", "")
        if not id_token or not state:
            raise LaunchRefused("the launch carries no id_token or no state")
        cookie_state = self._get_state_cookie()
        if not cookie_state or cookie_state != state:
            raise LaunchRefused("the launch's state is not the one this browser's login started (a forged or "
                                "replayed launch, or the browser dropped the hub's cookie)")
        nonce_state = self._get_nonce_state_cookie()
        return id_token, get_nonce(nonce_state) if nonce_state else None


class ToolKeysHandler(BaseHandler):
    """The tool's public key set (the platform checks the tool's service requests with it)."""

    def get(self):
        self.set_header("Content-Type", "application/json")
        self.write(json.dumps(self.authenticator.tool_key.jwks()))


class ClassLTIConfigHandler(LTI13ConfigHandler):
    """The tool's registration for Canvas ("Paste JSON" or "Enter URL" in the Developer Keys page)."""

    async def get(self):
        protocol = self.authenticator.get_uri_scheme(self.request)
        hub = f"{protocol}://{self.request.host}{self.hub.server.base_url}"
        launch = f"{protocol}://{self.request.host}{self.base_url}"  # then the student's own server
        self.set_header("Content-Type", "application/json")
        self.write(json.dumps({
            "title": self.authenticator.tool_name, "description": self.authenticator.tool_description,
            "oidc_initiation_url": url_path_join(hub, "lti13", "oauth_login"),
            "target_link_uri": launch,
            "public_jwk_url": url_path_join(hub, "lti13", "jwks"),
            "scopes": list(SCOPES),
            "extensions": [{"platform": "canvas.instructure.com", "privacy_level": "public", "settings": {
                # A new window: in the course page's frame, browsers that block third-party cookies
                # would drop the hub's state and nonce cookies, and every launch would be refused.
                "placements": [{"placement": "course_navigation", "message_type": "LtiResourceLinkRequest",
                                "target_link_uri": launch, "text": self.authenticator.tool_name,
                                "windowTarget": "_blank"}]}}],
        }))


class ClassLTIAuthenticator(LTI13Authenticator):
    """LTI 1.3 launches from one platform as the class's login (see the module's docstring)."""

    login_service = "your course page"
    login_handler = ClassLTILoginInitHandler
    callback_handler = ClassLTICallbackHandler
    config_handler = ClassLTIConfigHandler

    deployment_ids = Set(Unicode(), help="The deployments of the tool this hub serves (the platform shows "
                                         "the id when the tool is added to a course or site).").tag(config=True)
    roster_path = Unicode(help="The class roster (CSV): launches add their person to it.").tag(config=True)
    state_path = Unicode(help="The hub's state folder (the tool's key, platform ids, service URLs).").tag(config=True)
    login_prefix = Unicode(LOGIN_PREFIX, help="How platform users' logins start.").tag(config=True)
    max_age_seconds = Integer(600, help="How old a launch's token may be.").tag(config=True)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.tool_key = ToolKey.load_or_create(Path(self.state_path) / "lti-tool-key.pem")
        self.verifier = LaunchVerifier(self.issuer, self.client_id, self.deployment_ids, self.jwks_endpoint,
                                       self.max_age_seconds)

    def get_handlers(self, app):
        return [*super().get_handlers(app), ("/lti13/jwks", ToolKeysHandler)]

    @property
    def platform_ids_path(self) -> Path:
        return Path(self.state_path) / "lti-platform-ids.json"

    def check_allowed(self, username, authentication=None):
        # A verified launch of this course's platform and deployment is the permission; a person
        # the roster sync dropped cannot launch (the platform no longer lists them in the course).
        return username in read_roster(self.roster_path) or authentication is not None

    async def refresh_user(self, user, handler=None):
        # A student dropped by ``class_admin.py lti-sync`` loses their session at the next refresh.
        return user.name in read_roster(self.roster_path)

    async def authenticate(self, handler, data=None):
        if not isinstance(data, VerifiedLaunch):
            # Not a launch this hub verified: a form posted to /hub/login, say, naming any iss and sub.
            self.log.warning("LTI login refused: not a verified launch (%s)",
                             getattr(getattr(handler, "request", None), "path", "?"))
            return None
        claims = data
        login = login_for(claims["iss"], claims["sub"], self.login_prefix)
        entry = RosterEntry(login, platform_name(claims.get("name")), platform_email(claims.get("email")),
                            role_for(claims.get(LTI + "roles", [])))
        self._remember(entry, claims)
        self.log.info("LTI launch: %s as %s (%s)", login, entry.role, claims.get(LTI + "context", {}).get("id", "-"))
        return {"name": login, "admin": entry.is_admin}

    def _remember(self, entry: RosterEntry, claims: dict) -> None:
        """The person on the roster, their platform id, and (from an instructor's launch) the course's service URLs."""
        state = Path(self.state_path)
        with open(state / "lti.lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            roster = read_roster(self.roster_path)
            if entry.login not in roster or roster.entry(entry.login) != entry:
                write_roster(roster.with_entry(entry), self.roster_path)
            ids = read_platform_ids(self.platform_ids_path)
            if ids.get(entry.login) != claims["sub"]:
                write_private_json(self.platform_ids_path, dict(ids, **{entry.login: claims["sub"]}))
            if entry.is_admin:
                services = {"issuer": claims["iss"],
                            "context_id": claims.get(LTI + "context", {}).get("id", ""),
                            "memberships_url": claims.get(NRPS_CLAIM, {}).get("context_memberships_url", ""),
                            "lineitems_url": claims.get(AGS_CLAIM, {}).get("lineitems", "")}
                write_private_json(state / "lti-services.json", services)



#: The settings of an LTI hub (environment variables, as the rest of jupyterhub_config.py's).
SETTINGS = {
    "MT_HUB_LTI_ISSUER": "the platform's issuer (Canvas: https://canvas.instructure.com; Moodle: the site's URL)",
    "MT_HUB_LTI_CLIENT_ID": "the tool's client id the platform gave at registration",
    "MT_HUB_LTI_DEPLOYMENT_ID": "the deployment id(s) of the tool, comma-separated",
    "MT_HUB_LTI_AUTH_URL": "the platform's OIDC authorization URL (Moodle: Authentication request URL)",
    "MT_HUB_LTI_JWKS_URL": "the platform's public keyset URL",
}


def configure_lti(c, roster_path, state_path, environ) -> None:
    """Makes the hub of config ``c`` take LTI 1.3 launches as its login, from ``environ``'s settings.

    Raises:
        SystemExit: a setting is missing, naming each.
    """
    missing = [f"{name}: {what}" for name, what in SETTINGS.items() if not environ.get(name)]
    if missing:
        raise SystemExit("MT_HUB_LOGIN=lti needs the platform's settings (docs/guide/lms.md):\n  "
                         + "\n  ".join(missing))
    c.JupyterHub.authenticator_class = ClassLTIAuthenticator
    # The hub's request log shows each redirect's URL with the parameters it knows to be secret
    # hidden; the login initiation's redirect to the platform also carries the launch's nonce and
    # the platform's login hints: hidden too (matched as substrings, as the hub's own are).
    hidden = jupyterhub.log.SCRUB_PARAM_KEYS
    jupyterhub.log.SCRUB_PARAM_KEYS = (*hidden, *(key for key in ("nonce", "hint", "id_token") if key not in hidden))
    c.ClassLTIAuthenticator.issuer = environ["MT_HUB_LTI_ISSUER"]
    c.ClassLTIAuthenticator.client_id = {environ["MT_HUB_LTI_CLIENT_ID"]}
    c.ClassLTIAuthenticator.deployment_ids = {d.strip() for d in environ["MT_HUB_LTI_DEPLOYMENT_ID"].split(",")
                                              if d.strip()}
    c.ClassLTIAuthenticator.authorize_url = environ["MT_HUB_LTI_AUTH_URL"]
    c.ClassLTIAuthenticator.jwks_endpoint = environ["MT_HUB_LTI_JWKS_URL"]
    c.ClassLTIAuthenticator.login_prefix = environ.get("MT_HUB_LTI_LOGIN_PREFIX", LOGIN_PREFIX)
    c.ClassLTIAuthenticator.roster_path = str(roster_path)
    c.ClassLTIAuthenticator.state_path = str(state_path)
    c.ClassLTIAuthenticator.tool_name = "mt-widgets"
    c.ClassLTIAuthenticator.tool_description = "Teach a robot by demonstration, with machine-teaching guidance"
