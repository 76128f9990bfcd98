"""The class hub in a learning platform, end to end on loopback as root: LTI 1.3 launches from the test platform
(tests/course/lti_platform.py) as the hub's login (``MT_HUB_LOGIN=lti``), the roster synced from NRPS, grades
posted with AGS and read back from the platform.

- three students and an instructor launch the tool as a browser does (login initiation at the hub, the
  platform's authorization endpoint, the form posted back); each student lands in their own server as
  their own system user, the instructor is an admin in the instructors' group;
- a launch from another platform or deployment, an expired one, a badly signed one, one without a nonce
  and a replayed one are each refused with a page saying why and a log line, and no token is logged;
- ``lti_admin.py sync`` adds a newly enrolled student and drops one who left (their home is kept);
- ``lti_admin.py grades`` posts an nbgrader assignment's totals, read back from the platform's line item.

Hub tier; about 40 s on two cores (four servers, started the usual way).
"""

from __future__ import annotations

import grp
import html
import json
import os
import pwd
import re
import subprocess
import sys
import warnings
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import psutil
import pytest
import requests

from .hub_support import REPO, TEST_INSTRUCTORS, TEST_PREFIX, ClassHub, remove_leftovers_unless_busy
from .lti_platform import INSTRUCTOR, LTIPlatform, Member, new_key

sys.path.insert(0, str(REPO / "deploy" / "jupyterhub"))
from lti_services import login_for  # noqa: E402
from nbgrader.api import Gradebook  # noqa: E402

from mt_widgets.classroom.names import read_names  # noqa: E402

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(os.geteuid() != 0, reason="the class hub makes system users: run as root")]

LTI_ADMIN = REPO / "deploy" / "jupyterhub" / "lti_admin.py"
STUDENTS = {"sub-ann-1": "Ann Lee", "sub-bo-2": "Bo Chen", "sub-cy-3": "Cy Young"}
TEACHER, LATE = "sub-dana-9", "sub-eve-4"


@pytest.fixture(scope="module")
def course():
    """The platform with the course's people and the tool registered, and the hub taking its launches."""
    left = remove_leftovers_unless_busy()
    if left:
        warnings.warn(f"removed {len(left)} test accounts an earlier, killed run left", stacklevel=2)
    with LTIPlatform() as platform:
        for sub, name in STUDENTS.items():
            platform.enrol(Member(sub, name, f"{name.split()[0].lower()}@example.edu"))
        platform.enrol(Member(TEACHER, "Dana Scully", "dana@example.edu", (INSTRUCTOR,)))
        tool = platform.register_tool([], "", deployment_id="deployment-7")
        env = {"MT_HUB_LOGIN": "lti", "MT_HUB_LTI_ISSUER": platform.url, "MT_HUB_LTI_CLIENT_ID": tool.client_id,
               "MT_HUB_LTI_DEPLOYMENT_ID": tool.deployment_id, "MT_HUB_LTI_AUTH_URL": platform.auth_url,
               "MT_HUB_LTI_JWKS_URL": platform.jwks_url, "MT_HUB_LTI_TOKEN_URL": platform.token_url,
               "MT_HUB_LTI_LOGIN_PREFIX": TEST_PREFIX, "MT_HUB_SERVER_TEMPLATE": "off"}
        hub = ClassHub([], env=env)
        try:
            # The tool's URLs as the platform's administrator registers them (the hub's own config JSON).
            config = requests.get(f"{hub.url}/hub/lti13/config", timeout=30).json()
            tool.redirect_uris = (config["oidc_initiation_url"].replace("oauth_login", "oauth_callback"),)
            tool.target_link_uri, tool.jwks_url = config["target_link_uri"], config["public_jwk_url"]
            yield platform, tool, hub
        finally:
            hub.stop()
            hub.kept_log.unlink()
    assert not [user.pw_name for user in pwd.getpwall() if user.pw_name.startswith(TEST_PREFIX)]


def _login_initiation(hub, platform, tool, sub) -> tuple[requests.Session, dict]:
    """The platform's third-party login at the hub: the browser and the hub's authentication request."""
    browser = requests.Session()
    answer = browser.post(f"{hub.url}/hub/lti13/oauth_login", data=platform.login_initiation(tool, sub),
                          allow_redirects=False, timeout=60)
    assert answer.status_code == 302, answer.text[:500]
    target = urlparse(answer.headers["Location"])
    assert f"{target.scheme}://{target.netloc}{target.path}" == platform.auth_url
    return browser, {k: v[0] for k, v in parse_qs(target.query).items()}


def _post_launch(hub, browser, action, fields) -> requests.Response:
    return browser.post(action, data=fields, allow_redirects=False, timeout=120)


def launch(hub, platform, tool, sub) -> tuple[requests.Session, str]:
    """A person's click on the tool link, as a browser follows it; returns the browser and their login."""
    browser, request = _login_initiation(hub, platform, tool, sub)
    page = browser.get(platform.auth_url, params=request, timeout=60)
    assert page.status_code == 200, page.text[:500]
    action = html.unescape(re.search(r'action="([^"]+)"', page.text).group(1))
    fields = {html.unescape(n): html.unescape(v)
              for n, v in re.findall(r'name="([^"]+)" value="([^"]*)"', page.text)}
    answer = _post_launch(hub, browser, action, fields)
    assert answer.status_code == 302, f"{answer.status_code}: {answer.text[:800]}\n{hub.tail()}"
    assert any(cookie.name.startswith("jupyterhub-session") for cookie in browser.cookies)
    login = _login_of(hub, sub)
    hub.students.append(login)  # removed with the hub's accounts at the end
    return browser, login


def _login_of(hub, sub) -> str:
    ids = json.loads((hub.root / "state" / "lti-platform-ids.json").read_text())
    return next(login for login, platform_id in ids.items() if platform_id == sub)


def refused(hub, platform, tool, token_for, reason: str) -> None:
    """A launch whose id_token is ``token_for(nonce)`` gets a 403 page and a log line naming ``reason``."""
    browser, request = _login_initiation(hub, platform, tool, next(iter(STUDENTS)))
    answer = _post_launch(hub, browser, request["redirect_uri"],
                          {"id_token": token_for(request["nonce"]), "state": request["state"]})
    assert answer.status_code == 403, answer.text[:500]
    assert reason in html.unescape(answer.text) and "from your course page" in html.unescape(answer.text)
    assert [line for line in hub.tail(100_000).splitlines() if "LTI launch refused:" in line and reason in line]
    assert not any(cookie.name.startswith("jupyterhub-session") for cookie in browser.cookies)


@pytest.mark.timeout(600)
def test_students_and_an_instructor_launch_into_their_own_servers(course):
    platform, tool, hub = course
    browsers, logins = {}, {}
    for sub in [*STUDENTS, TEACHER]:
        browsers[sub], logins[sub] = launch(hub, platform, tool, sub)
    # Logins come from the platform's ids, not the names: safe system user names, one each.
    assert len(set(logins.values())) == 4 and all(login.startswith(TEST_PREFIX) for login in logins.values())
    roster = (hub.root / "roster.csv").read_text()
    assert "Ann Lee" in roster and "dana@example.edu" in roster
    users = {user["name"]: user for user in hub.api("GET", "/users")}
    assert users[logins[TEACHER]]["admin"] and not any(users[logins[sub]]["admin"] for sub in STUDENTS)
    for sub in [*STUDENTS, TEACHER]:
        hub.spawn(logins[sub])
    for sub in STUDENTS:
        login = logins[sub]
        # Their own server, reached with the session the launch gave them, as their own system user.
        assert browsers[sub].get(hub.user_url(login, "/"), timeout=120).status_code == 200
        answer = browsers[sub].get(hub.user_url(login, "/api/contents"), timeout=60)
        assert answer.status_code == 200 and answer.json()["type"] == "directory"
        account = pwd.getpwnam(login)
        assert account.pw_dir == str(hub.homes / login) and oct(os.stat(account.pw_dir).st_mode & 0o777) == "0o700"
        assert {process.uids().real for process in hub.processes(login)} == {account.pw_uid}
    # A student's session does not open a classmate's server.
    ann, bo = (logins[sub] for sub in list(STUDENTS)[:2])
    assert browsers[list(STUDENTS)[0]].get(hub.user_url(bo, "/"), timeout=60).status_code == 403
    assert logins[TEACHER] in grp.getgrnam(TEST_INSTRUCTORS).gr_mem
    assert ann not in grp.getgrnam(TEST_INSTRUCTORS).gr_mem
    # The tool's private key is the hub user's (root's) alone.
    key = hub.root / "state" / "lti-tool-key.pem"
    assert oct(key.stat().st_mode & 0o777) == "0o600" and key.stat().st_uid == 0


@pytest.mark.timeout(300)
def test_wrong_launches_are_refused_with_a_page_and_a_log_line(course):
    platform, tool, hub = course
    ann = next(iter(STUDENTS))
    refused(hub, platform, tool, lambda nonce: platform.id_token(tool, ann, nonce, issuer="https://lms.example.org"),
            "comes from another platform")
    refused(hub, platform, tool, lambda nonce: platform.id_token(tool, ann, nonce, deployment_id="deployment-8"),
            "comes from another deployment")
    refused(hub, platform, tool, lambda nonce: platform.id_token(tool, ann, nonce, lifetime_s=30, issued_ago_s=90),
            "has expired")
    refused(hub, platform, tool, lambda nonce: platform.id_token(tool, ann, nonce, key=new_key()),
            "signature is wrong")
    refused(hub, platform, tool, lambda nonce: platform.id_token(tool, ann, None), "has no nonce")
    # The login initiation itself: from another platform, or with no platform at all (the hub's login page).
    initiation = dict(platform.login_initiation(tool, ann), iss="https://lms.example.org")
    answer = requests.post(f"{hub.url}/hub/lti13/oauth_login", data=initiation, allow_redirects=False, timeout=60)
    assert answer.status_code == 403 and "comes from another platform" in html.unescape(answer.text)
    answer = requests.get(f"{hub.url}/hub/lti13/oauth_login", allow_redirects=False, timeout=60)
    assert answer.status_code == 400 and "open mt-widgets from your course page" in html.unescape(answer.text)
    # A replay: the same launch posted again with the cookies of the browser that made it.
    browser, request = _login_initiation(hub, platform, tool, ann)
    cookies = browser.cookies.copy()
    fields = {"id_token": platform.id_token(tool, ann, request["nonce"]), "state": request["state"]}
    assert _post_launch(hub, browser, request["redirect_uri"], fields).status_code == 302
    replay = requests.Session()
    replay.cookies = cookies
    answer = _post_launch(hub, replay, request["redirect_uri"], fields)
    assert answer.status_code == 403 and "used before" in html.unescape(answer.text)
    # JupyterHub's own login form, posted with the course's issuer and a classmate's platform id.
    users = {user["name"] for user in hub.api("GET", "/users")}
    for victim in (ann, "sub-zed-0"):   # a classmate, and a platform id nobody launched with
        forger = requests.Session()
        forger.get(f"{hub.url}/hub/login", timeout=60)
        answer = forger.post(f"{hub.url}/hub/login", allow_redirects=False, timeout=60,
                             data={"_xsrf": forger.cookies.get("_xsrf", ""), "iss": platform.url, "sub": victim,
                                   "username": "x", "password": "x"})
        assert answer.status_code != 302, answer.headers
        assert forger.get(f"{hub.url}/hub/api/user", timeout=60).status_code == 403
    assert {user["name"] for user in hub.api("GET", "/users")} == users
    assert "LTI login refused: not a verified launch" in hub.tail(200_000)
    log = hub.tail(200_000)
    assert log.count("LTI launch refused:") >= 7
    # Tokens and launches are never logged whole.
    assert fields["id_token"] not in log and fields["id_token"].split(".")[1] not in log
    assert request["nonce"] not in log


@pytest.mark.timeout(300)
def test_the_roster_follows_the_platform_and_grades_go_back(course, monkeypatch):
    platform, tool, hub = course
    monkeypatch.setenv("PATH", f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")  # nbgrader's alembic
    subs = list(STUDENTS)
    logins = {sub: _login_of(hub, sub) for sub in subs}
    dropped = logins[subs[2]]
    platform.drop(subs[2])
    platform.enrol(Member(LATE, "Eve Late"))
    env = dict(hub.env)
    teacher = _login_of(hub, TEACHER)
    names = hub.homes / teacher / "class-names.json"
    result = subprocess.run([sys.executable, str(LTI_ADMIN), "sync", "--names", str(names), "--names-owner", teacher],
                            capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    late = _login_of(hub, LATE)
    hub.students.append(late)
    roster = (hub.root / "roster.csv").read_text()
    assert late in roster and "Eve Late" in roster and dropped not in roster
    assert f"dropped {dropped}" in result.stdout and f"added {late} as student" in result.stdout
    # The class view's names: the platform's, for the instructor's eyes only.
    assert names.stat().st_uid == pwd.getpwnam(teacher).pw_uid and oct(names.stat().st_mode & 0o777) == "0o600"
    shown = set(read_names(names).values())
    assert {"Ann Lee", "Bo Chen", "Eve Late"} <= shown and "Cy Young" not in shown and "Dana Scully" not in shown
    # Their files are kept; their server and kernels are ended (dead, if the hub has not reaped them yet).
    assert (hub.homes / dropped).is_dir()
    assert all(process.status() == psutil.STATUS_ZOMBIE for process in hub.processes(dropped))

    assert login_for(platform.url, subs[0], TEST_PREFIX) == logins[subs[0]]
    with Gradebook(f"sqlite:///{hub.course / 'gradebook.db'}") as gradebook:
        gradebook.add_assignment("a1_ridge_learner")
        gradebook.add_notebook("ridge", "a1_ridge_learner")
        gradebook.add_grade_cell("fit", "ridge", "a1_ridge_learner", max_score=5, cell_type="code")
        for sub, points in zip(subs[:2], (5, 3)):
            gradebook.add_student(logins[sub])
            gradebook.add_submission("a1_ridge_learner", logins[sub])
            grade = gradebook.find_grade("fit", "ridge", "a1_ridge_learner", logins[sub])
            grade.auto_score, grade.needs_manual_grade = points, False
        gradebook.db.commit()
    result = subprocess.run([sys.executable, str(LTI_ADMIN), "grades"], capture_output=True, text=True, env=env,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    [item] = platform.line_items()
    assert item["label"] == "a1_ridge_learner" and item["scoreMaximum"] == 5
    assert platform.result_of(item["id"], subs[0])["scoreGiven"] == 5
    assert platform.result_of(item["id"], subs[1])["scoreGiven"] == 3
