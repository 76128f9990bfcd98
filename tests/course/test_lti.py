"""The hub as an LTI 1.3 tool, without a hub: the launch check, logins and roles, the tool's key, and the
NRPS roster sync, against the test platform (tests/course/lti_platform.py) on 127.0.0.1.

The end-to-end launch through a running hub is tests/course/test_hub_lti.py.
"""

from __future__ import annotations

import os
import sys

import pytest

from mt_widgets.classroom.roster import LOGIN_PATTERN, Roster, RosterEntry

from .course_support import REPO
from .lti_platform import INSTRUCTOR, LEARNER, TEACHING_ASSISTANT, LTIPlatform, Member, new_key

sys.path.insert(0, str(REPO / "deploy" / "jupyterhub"))
from lti_authenticator import ClassLTIAuthenticator, LaunchRefused, LaunchVerifier, VerifiedLaunch  # noqa: E402
from lti_services import LTIServiceError, PlatformClient, ToolKey, login_for, role_for, synced_roster  # noqa: E402

ANN, BO, CY, DANA = "sub-ann-7f3", "sub-bo-11c", "sub-cy-90d", "sub-dana-2b"


@pytest.fixture(scope="module")
def platform():
    with LTIPlatform() as running:
        running.enrol(Member(ANN, "Ann Lee", "ann@example.edu"))
        running.enrol(Member(BO, "Bo Chen"))
        running.enrol(Member(DANA, "Dana Scully", "dana@example.edu", (INSTRUCTOR,)))
        yield running


@pytest.fixture(scope="module")
def tool_key(tmp_path_factory):
    return ToolKey.load_or_create(tmp_path_factory.mktemp("tool") / "key.pem")


@pytest.fixture(scope="module")
def tool(platform, tool_key):
    return platform.register_tool(["https://hub.example.edu/hub/lti13/oauth_callback"], "https://hub.example.edu/",
                                  jwks=tool_key.jwks(), deployment_id="dep-1")


@pytest.fixture
def verifier(platform, tool):
    return LaunchVerifier(platform.url, {tool.client_id}, {tool.deployment_id}, platform.jwks_url)


def test_a_launch_from_the_course_platform_is_accepted_with_its_claims(platform, tool, verifier):
    claims = verifier.verify(platform.id_token(tool, ANN, "nonce-a"), "nonce-a")
    assert claims["sub"] == ANN and claims["name"] == "Ann Lee"
    assert claims["https://purl.imsglobal.org/spec/lti/claim/deployment_id"] == "dep-1"


@pytest.mark.parametrize("wrong, reason", [
    ("issuer", "another platform"),
    ("deployment", "another deployment"),
    ("expired", "expired"),
    ("signature", "signature is wrong"),
    ("unknown key", "not in the platform's key set"),
    ("no nonce", "has no nonce"),
    ("other nonce", "nonce is not the one this browser's login started"),
    ("other tool", "meant for another tool"),
])
def test_a_wrong_launch_is_refused_naming_what_is_wrong(platform, tool, verifier, wrong, reason):
    nonce = f"nonce-{wrong}"
    token = {
        "issuer": lambda: platform.id_token(tool, ANN, nonce, issuer="https://other-platform.example.edu"),
        "deployment": lambda: platform.id_token(tool, ANN, nonce, deployment_id="dep-2"),
        "expired": lambda: platform.id_token(tool, ANN, nonce, lifetime_s=60, issued_ago_s=120),
        # Signed with another key under the platform's own key id: the signature does not verify.
        "signature": lambda: platform.id_token(tool, ANN, nonce, key=new_key()),
        "unknown key": lambda: _with_kid(platform.id_token(tool, ANN, nonce, key=new_key()), "kid-unknown"),
        "no nonce": lambda: platform.id_token(tool, ANN, None),
        "other nonce": lambda: platform.id_token(tool, ANN, "a nonce this browser never sent"),
        "other tool": lambda: platform.id_token(tool, ANN, nonce, claims={"aud": "client-other", "azp": "x"}),
    }[wrong]()
    with pytest.raises(LaunchRefused, match=reason):
        verifier.verify(token, nonce)


def test_a_replayed_launch_is_refused(platform, tool, verifier):
    token = platform.id_token(tool, BO, "nonce-once")
    verifier.verify(token, "nonce-once")
    with pytest.raises(LaunchRefused, match="used before"):
        verifier.verify(token, "nonce-once")
    # Replayed into another browser's login (whose nonce differs): refused too.
    with pytest.raises(LaunchRefused, match="not the one this browser's login started"):
        verifier.verify(token, "nonce-of-another-login")


def test_a_student_cannot_become_another_by_a_claim_they_can_reach(platform, tool, verifier):
    # The display name and e-mail are the student's to edit; the login comes from the platform's sub only.
    own = verifier.verify(platform.id_token(tool, ANN, "n1"), "n1")
    renamed = verifier.verify(platform.id_token(tool, ANN, "n2", claims={"name": "Bo Chen", "email": "bo@x.org"}),
                              "n2")
    assert login_for(own["iss"], own["sub"]) == login_for(renamed["iss"], renamed["sub"])
    assert login_for(platform.url, ANN) != login_for(platform.url, BO)
    # The same sub at another platform is another person.
    assert login_for("https://other.example.edu", ANN) != login_for(platform.url, ANN)


def test_logins_are_safe_system_user_names_and_roles_follow_the_context_role():
    login = login_for("https://canvas.instructure.com", "535fa085f22b4655f48cd5a36a9215f64c062838")
    assert LOGIN_PATTERN.fullmatch(login) and login.startswith("lti-") and len(login) == 20
    assert login_for("https://x", "1", prefix="mtt-").startswith("mtt-")
    with pytest.raises(ValueError, match="prefix"):
        login_for("https://x", "1", prefix="9-")
    with pytest.raises(ValueError, match="sub"):
        login_for("https://x", "")
    assert role_for([INSTRUCTOR]) == "instructor"
    assert role_for([TEACHING_ASSISTANT]) == "ta"
    assert role_for(["http://purl.imsglobal.org/vocab/lis/v2/membership/Instructor#TeachingAssistant"]) == "ta"
    assert role_for(["Instructor"]) == "instructor"  # the short form LTI allows for context roles
    assert role_for([LEARNER]) == "student"
    # A site administrator launching into a course as a learner gets no rights in it.
    assert role_for(["http://purl.imsglobal.org/vocab/lis/v2/institution/person#Administrator", LEARNER]) == "student"
    with pytest.raises(ValueError, match="roles"):
        role_for("Instructor")


def test_the_tools_private_key_is_its_owners_alone(tmp_path):
    path = tmp_path / "key.pem"
    key = ToolKey.load_or_create(path)
    assert oct(path.stat().st_mode & 0o777) == "0o600"
    assert ToolKey.load_or_create(path).kid == key.kid  # loaded again, not made again
    assert "d" not in key.jwks()["keys"][0] and key.jwks()["keys"][0]["kid"] == key.kid  # public half only
    os.chmod(path, 0o640)
    with pytest.raises(PermissionError, match="chmod 600"):
        ToolKey.load_or_create(path)


def test_the_platform_grants_a_token_only_for_the_tools_own_key(platform, tool, tool_key):
    client = PlatformClient(tool.client_id, platform.token_url, tool_key)
    members = client.members(platform.memberships_url + "?limit=2")  # three members: two pages
    assert sorted(m["user_id"] for m in members) == sorted(platform.members)
    impostor = PlatformClient(tool.client_id, platform.token_url, ToolKey(new_key()))
    with pytest.raises(LTIServiceError, match="refused the tool"):
        impostor.members(platform.memberships_url)


def test_the_roster_sync_adds_and_drops_platform_members_and_keeps_local_ones(platform, tool, tool_key):
    client = PlatformClient(tool.client_id, platform.token_url, tool_key)
    local_ta = RosterEntry("tom", "Tom Hart", role="ta")
    first = synced_roster(Roster((local_ta,)), client.members(platform.memberships_url), platform.url)
    ann, bo, dana = (login_for(platform.url, sub) for sub in (ANN, BO, DANA))
    assert set(first.added) == {ann, bo, dana} and first.dropped == ()
    assert first.roster.entry(ann).name == "Ann Lee" and first.roster.entry(ann).email == "ann@example.edu"
    assert first.roster.entry(dana).role == "instructor" and first.roster.entry(bo).role == "student"
    assert first.platform_ids[ann] == ANN
    platform.enrol(Member(CY, "Cy Twombly\n<script>"))  # a name a platform may hand over, made one clean line
    platform.drop(BO)
    try:
        second = synced_roster(first.roster, client.members(platform.memberships_url), platform.url,
                               platform_ids=first.platform_ids)
    finally:
        platform.drop(CY)
        platform.enrol(Member(BO, "Bo Chen"))
    cy = login_for(platform.url, CY)
    assert second.added == (cy,) and second.dropped == (bo,)
    assert second.roster.entry(cy).name == "Cy Twombly <script>"
    assert "tom" in second.roster and bo not in second.roster and ann in second.roster


def _with_kid(token: str, kid: str) -> str:
    import base64
    import json

    header, payload, signature = token.split(".")
    decoded = json.loads(base64.urlsafe_b64decode(header + "=" * (-len(header) % 4)))
    decoded["kid"] = kid
    new_header = base64.urlsafe_b64encode(json.dumps(decoded).encode()).rstrip(b"=").decode()
    return ".".join([new_header, payload, signature])


def test_only_a_verified_launch_signs_anyone_in_not_a_form_naming_an_issuer_and_a_sub(tmp_path):
    # JupyterHub's own /hub/login takes a POST and hands its form fields to the authenticator: a form
    # naming the course's issuer and a classmate's platform id must not sign in as them.
    import asyncio

    roster = tmp_path / "roster.csv"
    roster.write_text("login,name,email,role\n")
    authenticator = ClassLTIAuthenticator(
        issuer="https://lms.example.edu", client_id={"tool-1"}, authorize_url="https://lms.example.edu/auth",
        jwks_endpoint="https://lms.example.edu/jwks", deployment_ids={"dep-1"}, roster_path=str(roster),
        state_path=str(tmp_path))
    forged = {"iss": "https://lms.example.edu", "sub": ANN}
    assert asyncio.run(authenticator.authenticate(None, forged)) is None
    assert roster.read_text() == "login,name,email,role\n"   # nobody added either
    signed_in = asyncio.run(authenticator.authenticate(None, VerifiedLaunch(forged)))
    assert signed_in == {"name": login_for("https://lms.example.edu", ANN), "admin": False}
