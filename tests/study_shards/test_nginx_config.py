"""The nginx configuration for several study servers (deploy/nginx/render_config.py): what it refuses, what it says."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "deploy" / "nginx"))
from render_config import render  # noqa: E402


def test_every_server_is_an_upstream_that_nginx_never_marks_failed_and_the_prefix_holds_every_file(tmp_path):
    text = render(["127.0.0.1:9001", "10.0.0.12:8866"], "127.0.0.1:8080", tmp_path)
    assert "server 127.0.0.1:9001 max_fails=0;" in text and "server 10.0.0.12:8866 max_fails=0;" in text
    assert "hash $mt_route consistent;" in text and "proxy_next_upstream off;" in text
    assert not re.search(r"\{\{[A-Z_]+\}\}", text) and "listen 127.0.0.1:8080;" in text
    for directive in ("pid", "error_log", "access_log", "client_body_temp_path", "proxy_temp_path"):
        assert f"{directive} {tmp_path}/" in text, directive
    assert "SameSite=Lax; Secure" in text
    assert "access_log" in text and "mt_no_query;" in text and "$request " not in text and "$args" not in text
    plain = render(["127.0.0.1:9001"], "8080", tmp_path, secure_cookie=False)
    assert "SameSite=Lax\";" in plain and "Secure" not in plain


@pytest.mark.parametrize("servers, listen, prefix, secure, words", [
    ([], "80", "/srv/x", True, "at least one"),
    (["10.0.0.1"], "80", "/srv/x", True, "'host:port'"),
    (["10.0.0.1:80; evil"], "80", "/srv/x", True, "'host:port'"),
    (["10.0.0.1:80", "10.0.0.1:80"], "80", "/srv/x", True, "each address once"),
    (["10.0.0.1:80"], "80;", "/srv/x", True, "listen"),
    (["10.0.0.1:80"], "80", "relative/x", True, "absolute"),
    (["10.0.0.1:80"], "80", "/srv/a b", True, "without spaces"),
])
def test_a_value_that_would_break_the_configuration_is_refused_naming_it(servers, listen, prefix, secure, words):
    with pytest.raises(ValueError, match=words):
        render(servers, listen, prefix, secure_cookie=secure)


def test_secure_cookie_accepts_only_a_bool():
    with pytest.raises(TypeError, match="secure_cookie"):
        render(["10.0.0.1:80"], "80", "/srv/x", secure_cookie="no")
