"""A learning platform for tests: an LTI 1.3 platform with LTI Advantage's services, on 127.0.0.1.

It plays the part Canvas or Moodle plays for the class hub, after 1EdTech's specifications:

- **Security Framework 1.0** (https://www.imsglobal.org/spec/security/v1p0/): its own RSA key
  pair, its public key set at ``/jwks``; the OpenID Connect authorization endpoint ``/auth``
  that answers a tool's authentication request (``response_type=id_token``, ``response_mode=
  form_post``, ``prompt=none``, the registered ``redirect_uri``) with a page that posts a signed
  ``id_token`` and the ``state`` to the tool; the OAuth 2 token endpoint ``/token`` for the
  client-credentials grant with a JWT assertion signed by the tool's key (checked against the
  tool's key set, ``aud`` the token endpoint, a ``jti`` used once).
- **LTI Core 1.3** (https://www.imsglobal.org/spec/lti/v1p3/): the resource link launch's claims
  (message_type, version, deployment_id, target_link_uri, resource_link, roles, context, sub,
  name, email) and the two service claims below.
- **Names and Role Provisioning Services 2.0** (https://www.imsglobal.org/spec/lti-nrps/v2p0):
  ``/nrps/<context>/memberships``, paged with ``limit`` and a ``Link: rel="next"`` header.
- **Assignment and Grade Services 2.0** (https://www.imsglobal.org/spec/lti-ags/v2p0): line
  items (``/ags/<context>/lineitems``: list, filter by ``resource_id``/``tag``, create; each
  line item read, its ``/scores`` posted, its ``/results`` read). A score older than the
  one kept for that person is ignored, as the specification asks of a platform.

Each service call needs a bearer token granted for the service's scope. Everything is in memory;
the test drives the people (``enrol``, ``drop``) and reads what the tool did (``line_items``,
``results``, ``scores_received``).
"""

from __future__ import annotations

import base64
import html
import json
import secrets
import threading
import time
import uuid
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, urlencode, urlparse

import jwt
import requests
from cryptography.hazmat.primitives.asymmetric import rsa

LTI = "https://purl.imsglobal.org/spec/lti/claim/"
NRPS_CLAIM = "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice"
AGS_CLAIM = "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint"
SCOPE_MEMBERSHIPS = "https://purl.imsglobal.org/spec/lti-nrps/scope/contextmembership.readonly"
SCOPE_LINEITEM = "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem"
SCOPE_RESULTS = "https://purl.imsglobal.org/spec/lti-ags/scope/result.readonly"
SCOPE_SCORE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
ROLE = "http://purl.imsglobal.org/vocab/lis/v2/membership#"
LEARNER, INSTRUCTOR, TEACHING_ASSISTANT = (ROLE + "Learner", ROLE + "Instructor",
                                           ROLE + "Instructor#TeachingAssistant")
ASSERTION_TYPE = "urn:ietf:params:oauth:client-assertion-type:jwt-bearer"


def new_key() -> rsa.RSAPrivateKey:
    return rsa.generate_private_key(public_exponent=65537, key_size=2048)


def public_jwk(key: rsa.RSAPrivateKey, kid: str) -> dict:
    """The public half of ``key`` as a JSON Web Key (RFC 7517) for RS256 signatures."""
    numbers = key.public_key().public_numbers()

    def b64(number: int) -> str:
        return base64.urlsafe_b64encode(number.to_bytes((number.bit_length() + 7) // 8, "big")).rstrip(b"=").decode()

    return {"kty": "RSA", "alg": "RS256", "use": "sig", "kid": kid, "n": b64(numbers.n), "e": b64(numbers.e)}


@dataclass
class Member:
    """A person of the platform's course: ``sub`` is the platform's stable user id."""

    sub: str
    name: str
    email: str = ""
    roles: tuple[str, ...] = (LEARNER,)
    status: str = "Active"


@dataclass
class Tool:
    """The tool as registered in the platform: its client id, deployment, launch URLs and key set."""

    client_id: str
    deployment_id: str
    redirect_uris: tuple[str, ...]
    target_link_uri: str
    jwks_url: str | None = None
    jwks: dict | None = None
    used_jtis: set = field(default_factory=set)


class LTIPlatform:
    """The test platform; ``url`` is its issuer. Use as a context manager, or ``start``/``stop``."""

    def __init__(self, context_id: str = "course-101", context_title: str = "Machine teaching 101"):
        self.key, self.kid = new_key(), f"platform-{secrets.token_hex(4)}"
        self.context_id, self.context_title = context_id, context_title
        self.members: dict[str, Member] = {}
        self.tools: dict[str, Tool] = {}
        self.tokens: dict[str, tuple[str, set, float]] = {}  # access token -> (client id, scopes, expiry)
        self.items: dict[str, dict] = {}  # line item id (its URL) -> line item
        self.results: dict[str, dict[str, dict]] = {}  # line item id -> user id -> score posted
        self.scores_received: list[dict] = []
        self.lock = threading.Lock()
        self._server = ThreadingHTTPServer(("127.0.0.1", 0), self._handler_class())
        self.url = f"http://127.0.0.1:{self._server.server_address[1]}"
        self._thread = threading.Thread(target=self._server.serve_forever, args=(0.05,), daemon=True)

    # -- the test's side ----------------------------------------------------------------------------
    def start(self) -> LTIPlatform:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._server.shutdown()
        self._server.server_close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    @property
    def jwks_url(self) -> str:
        return f"{self.url}/jwks"

    @property
    def auth_url(self) -> str:
        return f"{self.url}/auth"

    @property
    def token_url(self) -> str:
        return f"{self.url}/token"

    @property
    def memberships_url(self) -> str:
        return f"{self.url}/nrps/{self.context_id}/memberships"

    @property
    def lineitems_url(self) -> str:
        return f"{self.url}/ags/{self.context_id}/lineitems"

    def register_tool(self, redirect_uris, target_link_uri: str, jwks_url: str | None = None,
                      jwks: dict | None = None, deployment_id: str = "1") -> Tool:
        """Registers a tool (as an administrator does in Canvas or Moodle); returns it with its client id."""
        tool = Tool(f"client-{secrets.token_hex(4)}", deployment_id, tuple(redirect_uris), target_link_uri,
                    jwks_url, jwks)
        self.tools[tool.client_id] = tool
        return tool

    def enrol(self, member: Member) -> Member:
        self.members[member.sub] = member
        return member

    def drop(self, sub: str) -> None:
        """The person leaves the course (the platform's memberships no longer list them)."""
        del self.members[sub]

    def login_initiation(self, tool: Tool, sub: str) -> dict:
        """The third-party initiated login's parameters the platform sends the tool's login URL."""
        return {"iss": self.url, "login_hint": sub, "target_link_uri": tool.target_link_uri,
                "lti_message_hint": f"resource-link-1:{sub}", "client_id": tool.client_id,
                "lti_deployment_id": tool.deployment_id}

    def id_token(self, tool: Tool, sub: str, nonce: str | None, *, issuer: str | None = None,
                 deployment_id: str | None = None, lifetime_s: float = 300, issued_ago_s: float = 0,
                 key: rsa.RSAPrivateKey | None = None, claims: dict | None = None) -> str:
        """A signed launch (LtiResourceLinkRequest) of ``sub`` for ``tool``; the keyword arguments make
        the wrong ones a test needs (another issuer or deployment, expired, signed with another key)."""
        member = self.members[sub]
        now = time.time() - issued_ago_s
        payload = {
            "iss": issuer or self.url, "aud": tool.client_id, "azp": tool.client_id, "sub": sub,
            "iat": int(now), "exp": int(now + lifetime_s), "name": member.name, "email": member.email,
            LTI + "message_type": "LtiResourceLinkRequest", LTI + "version": "1.3.0",
            LTI + "deployment_id": deployment_id or tool.deployment_id,
            LTI + "target_link_uri": tool.target_link_uri,
            LTI + "resource_link": {"id": "resource-link-1", "title": "mt-widgets"},
            LTI + "roles": list(member.roles),
            LTI + "context": {"id": self.context_id, "label": "MT101", "title": self.context_title,
                              "type": ["http://purl.imsglobal.org/vocab/lis/v2/course#CourseOffering"]},
            LTI + "tool_platform": {"guid": self.kid, "name": "test platform", "product_family_code": "mt-tests"},
            NRPS_CLAIM: {"context_memberships_url": self.memberships_url, "service_versions": ["2.0"]},
            AGS_CLAIM: {"scope": [SCOPE_LINEITEM, SCOPE_RESULTS, SCOPE_SCORE], "lineitems": self.lineitems_url},
        }
        if nonce is not None:
            payload["nonce"] = nonce
        payload.update(claims or {})
        return jwt.encode(payload, key or self.key, algorithm="RS256", headers={"kid": self.kid})

    def authentication_response(self, params: dict, sub: str) -> tuple[str, dict]:
        """The platform's answer to a tool's authentication request ``params`` for the signed-in ``sub``:
        (the tool's redirect_uri, the form fields posted there). Raises ValueError on a request the
        Security Framework makes a platform refuse."""
        expected = {"response_type": "id_token", "scope": "openid", "response_mode": "form_post", "prompt": "none"}
        for name, value in expected.items():
            if params.get(name) != value:
                raise ValueError(f"authentication request: {name} must be {value!r}, got {params.get(name)!r}")
        tool = self.tools.get(params.get("client_id", ""))
        if tool is None:
            raise ValueError(f"authentication request: unknown client_id {params.get('client_id')!r}")
        if params.get("redirect_uri") not in tool.redirect_uris:
            raise ValueError(f"authentication request: redirect_uri {params.get('redirect_uri')!r} is not registered")
        if params.get("login_hint") != sub:
            raise ValueError("authentication request: login_hint is not the signed-in user")
        if not params.get("nonce"):
            raise ValueError("authentication request: no nonce")
        return params["redirect_uri"], {"id_token": self.id_token(tool, sub, params["nonce"]),
                                        "state": params.get("state", "")}

    def line_items(self) -> list[dict]:
        with self.lock:
            return [dict(item) for item in self.items.values()]

    def result_of(self, item_id: str, sub: str) -> dict | None:
        with self.lock:
            return self.results.get(item_id, {}).get(sub)

    # -- the HTTP side ------------------------------------------------------------------------------
    def _tool_jwks(self, tool: Tool) -> dict:
        if tool.jwks is not None:
            return tool.jwks
        return requests.get(tool.jwks_url, timeout=10).json()

    def _grant(self, form: dict) -> tuple[int, dict]:
        """The OAuth 2 token endpoint (RFC 6749 4.4, RFC 7523 assertion, the Security Framework 4.1)."""
        if form.get("grant_type") != "client_credentials" or form.get("client_assertion_type") != ASSERTION_TYPE:
            return 400, {"error": "unsupported_grant_type"}
        assertion = form.get("client_assertion", "")
        try:
            unverified = jwt.decode(assertion, options={"verify_signature": False})
            tool = self.tools[unverified["iss"]]
            keys = jwt.PyJWKSet.from_dict(self._tool_jwks(tool))
            kid = jwt.get_unverified_header(assertion).get("kid")
            key = next(k for k in keys.keys if k.key_id == kid)
            claims = jwt.decode(assertion, key.key, algorithms=["RS256"], audience=self.token_url,
                                issuer=tool.client_id, options={"require": ["exp", "iat", "jti", "sub"]})
        except (jwt.PyJWTError, KeyError, StopIteration, ValueError) as error:
            return 401, {"error": "invalid_client", "error_description": str(error)}
        if claims["sub"] != tool.client_id or claims["jti"] in tool.used_jtis:
            return 401, {"error": "invalid_client", "error_description": "sub is not the client, or jti reused"}
        tool.used_jtis.add(claims["jti"])
        allowed = {SCOPE_MEMBERSHIPS, SCOPE_LINEITEM, SCOPE_RESULTS, SCOPE_SCORE}
        scopes = set(form.get("scope", "").split()) & allowed
        if not scopes:
            return 400, {"error": "invalid_scope"}
        token = secrets.token_urlsafe(24)
        self.tokens[token] = (tool.client_id, scopes, time.time() + 3600)
        return 200, {"access_token": token, "token_type": "Bearer", "expires_in": 3600, "scope": " ".join(scopes)}

    def _authorised(self, header: str, scope: str) -> bool:
        token = header.removeprefix("Bearer ").strip() if header.startswith("Bearer ") else ""
        client, scopes, expiry = self.tokens.get(token, ("", set(), 0.0))
        return bool(client) and scope in scopes and time.time() < expiry

    def _memberships(self, query: dict) -> tuple[dict, str | None]:
        members = sorted(self.members.values(), key=lambda m: m.sub)
        limit = int(query.get("limit", ["100"])[0])
        offset = int(query.get("offset", ["0"])[0])
        page = members[offset:offset + limit]
        body = {"id": self.memberships_url,
                "context": {"id": self.context_id, "label": "MT101", "title": self.context_title},
                "members": [{"status": m.status, "name": m.name, "email": m.email, "user_id": m.sub,
                             "roles": list(m.roles)} for m in page]}
        following = None
        if offset + limit < len(members):
            following = f"{self.memberships_url}?{urlencode({'limit': limit, 'offset': offset + limit})}"
        return body, following

    def _handler_class(self):
        platform = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):  # quiet: the test reads state, not a log
                pass

            def _send(self, status: int, body, content_type: str = "application/json", headers=()):
                data = body.encode() if isinstance(body, str) else json.dumps(body).encode()
                self.send_response(status)
                self.send_header("Content-Type", content_type)
                self.send_header("Content-Length", str(len(data)))
                for name, value in headers:
                    self.send_header(name, value)
                self.end_headers()
                self.wfile.write(data)

            def _body(self) -> bytes:
                return self.rfile.read(int(self.headers.get("Content-Length") or 0))

            def _route(self, method: str):
                parsed = urlparse(self.path)
                path, query = parsed.path, parse_qs(parsed.query)
                auth = self.headers.get("Authorization", "")
                items_prefix = f"/ags/{platform.context_id}/lineitems"
                if method == "GET" and path == "/jwks":
                    return self._send(200, {"keys": [public_jwk(platform.key, platform.kid)]})
                if path == "/auth":
                    params = {k: v[0] for k, v in query.items()}
                    if method == "POST":
                        params.update({k: v[0] for k, v in parse_qs(self._body().decode()).items()})
                    # The signed-in user is the one the platform's own login hint named.
                    try:
                        action, fields = platform.authentication_response(params, params.get("login_hint", ""))
                    except (ValueError, KeyError) as error:
                        return self._send(400, {"error": "invalid_request", "error_description": str(error)})
                    inputs = "".join(f'<input type="hidden" name="{html.escape(k)}" value="{html.escape(v)}">'
                                     for k, v in fields.items())
                    page = (f'<form method="post" action="{html.escape(action)}">{inputs}</form>'
                            "<script>document.forms[0].submit()</script>")
                    return self._send(200, page, "text/html")
                if method == "POST" and path == "/token":
                    status, body = platform._grant({k: v[0] for k, v in parse_qs(self._body().decode()).items()})
                    return self._send(status, body)
                if method == "GET" and path == f"/nrps/{platform.context_id}/memberships":
                    if not platform._authorised(auth, SCOPE_MEMBERSHIPS):
                        return self._send(401, {"error": "invalid_token"})
                    with platform.lock:
                        body, following = platform._memberships(query)
                    links = [("Link", f'<{following}>; rel="next"')] if following else []
                    return self._send(200, body, "application/vnd.ims.lti-nrps.v2.membershipcontainer+json", links)
                if path == items_prefix:
                    if method == "GET":
                        if not (platform._authorised(auth, SCOPE_LINEITEM)
                                or platform._authorised(auth, "lineitem.readonly")):
                            return self._send(401, {"error": "invalid_token"})
                        wanted = {k: v[0] for k, v in query.items() if k in ("resource_id", "tag", "resource_link_id")}
                        key = {"resource_id": "resourceId", "tag": "tag", "resource_link_id": "resourceLinkId"}
                        items = [i for i in platform.line_items()
                                 if all(i.get(key[k]) == v for k, v in wanted.items())]
                        return self._send(200, items, "application/vnd.ims.lis.v2.lineitemcontainer+json")
                    if method == "POST":
                        if not platform._authorised(auth, SCOPE_LINEITEM):
                            return self._send(401, {"error": "invalid_token"})
                        item = json.loads(self._body())
                        if not isinstance(item.get("scoreMaximum"), (int, float)) or item["scoreMaximum"] <= 0 \
                                or not item.get("label"):
                            return self._send(400, {"error": "a line item needs a label and a scoreMaximum > 0"})
                        item["id"] = f"{platform.url}{items_prefix}/{uuid.uuid4().hex[:8]}"
                        with platform.lock:
                            platform.items[item["id"]] = item
                            platform.results[item["id"]] = {}
                        return self._send(201, item, "application/vnd.ims.lis.v2.lineitem+json")
                for item_id in list(platform.items):
                    item_path = urlparse(item_id).path
                    if path == item_path and method == "GET":
                        if not platform._authorised(auth, SCOPE_LINEITEM):
                            return self._send(401, {"error": "invalid_token"})
                        return self._send(200, platform.items[item_id], "application/vnd.ims.lis.v2.lineitem+json")
                    if path == item_path + "/scores" and method == "POST":
                        if not platform._authorised(auth, SCOPE_SCORE):
                            return self._send(401, {"error": "invalid_token"})
                        if self.headers.get("Content-Type") != "application/vnd.ims.lis.v1.score+json":
                            return self._send(415, {"error": "expected application/vnd.ims.lis.v1.score+json"})
                        return self._send(*platform._score(item_id, json.loads(self._body())))
                    if path == item_path + "/results" and method == "GET":
                        if not platform._authorised(auth, SCOPE_RESULTS):
                            return self._send(401, {"error": "invalid_token"})
                        with platform.lock:
                            results = [{"id": f"{item_id}/results/{sub}", "scoreOf": item_id, "userId": sub,
                                        "resultScore": score["scoreGiven"], "resultMaximum": score["scoreMaximum"],
                                        "comment": score.get("comment", "")}
                                       for sub, score in platform.results[item_id].items()
                                       if "user_id" not in query or sub == query["user_id"][0]]
                        return self._send(200, results, "application/vnd.ims.lis.v2.resultcontainer+json")
                return self._send(404, {"error": f"no {method} {path}"})

            def do_GET(self):
                self._route("GET")

            def do_POST(self):
                self._route("POST")

        return Handler

    def _score(self, item_id: str, score: dict) -> tuple[int, dict]:
        required = ("userId", "timestamp", "activityProgress", "gradingProgress")
        missing = [name for name in required if name not in score]
        if missing:
            return 400, {"error": f"score without {', '.join(missing)}"}
        if score["userId"] not in self.members:
            return 422, {"error": f"userId {score['userId']!r} is not in the course"}
        with self.lock:
            self.scores_received.append(dict(score, lineitem=item_id))
            kept = self.results[item_id].get(score["userId"])
            if kept is not None and kept["timestamp"] >= score["timestamp"]:
                return 409, {"error": "a score with the same or a later timestamp is already kept"}
            self.results[item_id][score["userId"]] = score
        return 204, ""
