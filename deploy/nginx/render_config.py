"""Writes the nginx configuration for several study servers from study-servers.conf.template.

Run: ``python deploy/nginx/render_config.py --listen 80 --prefix /srv/mt-nginx \\
      --server 10.0.0.11:8866 --server 10.0.0.12:8866 > /srv/mt-nginx/nginx.conf``
then ``nginx -p /srv/mt-nginx -c /srv/mt-nginx/nginx.conf`` (docs/guide/several-servers.md).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

TEMPLATE = Path(__file__).resolve().parent / "study-servers.conf.template"
_ADDRESS = re.compile(r"^[A-Za-z0-9.\-\[\]:]+:[0-9]{1,5}$")


def render(servers, listen: str, prefix, secure_cookie: bool = True) -> str:
    """The configuration text.

    Args:
        servers: the study servers' "host:port" addresses (at least one; order does not matter).
        listen: what nginx listens on ("80", "127.0.0.1:8080", "443 ssl" with your TLS lines added).
        prefix: an absolute folder for nginx's pid, logs and temporary files.
        secure_cookie: mark the routing cookie Secure (served over https; False for a plain-http pilot).
    """
    servers = list(servers)
    if not servers:
        raise ValueError("servers: expected at least one 'host:port', got none")
    for address in servers:
        if not isinstance(address, str) or not _ADDRESS.match(address):
            raise ValueError(f"servers: expected 'host:port' addresses, got {address!r}")
    if len(set(servers)) != len(servers):
        raise ValueError(f"servers: expected each address once, got {servers}")
    if not isinstance(secure_cookie, bool):
        raise TypeError(f"secure_cookie: expected True or False, got {secure_cookie!r}")
    prefix = Path(prefix)
    if not prefix.is_absolute() or any(ch in str(prefix) for ch in ";{}\"' \n"):
        raise ValueError(f"prefix: expected an absolute folder without spaces, quotes, ';' or braces, got {prefix}")
    if not isinstance(listen, str) or not re.match(r"^[A-Za-z0-9.:\[\] ]+$", listen):
        raise ValueError(f"listen: expected a port or address:port (e.g. '80', '127.0.0.1:8080'), got {listen!r}")
    lines = "\n".join(f"        server {address} max_fails=0;" for address in servers)
    return (TEMPLATE.read_text(encoding="utf-8").replace("{{SERVERS}}", lines).replace("{{LISTEN}}", listen)
            .replace("{{PREFIX}}", str(prefix)).replace("{{COOKIE_SECURE}}", "; Secure" if secure_cookie else ""))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server", action="append", required=True, help="a study server's host:port (repeat)")
    parser.add_argument("--listen", default="80", help="nginx's listen value (default 80)")
    parser.add_argument("--prefix", required=True, help="absolute folder for nginx's pid, logs, temporary files")
    parser.add_argument("--plain-http", action="store_true", help="no Secure flag on the cookie (a pilot on http)")
    args = parser.parse_args()
    try:
        print(render(args.server, args.listen, args.prefix, secure_cookie=not args.plain_http), end="")
    except (TypeError, ValueError) as error:
        parser.error(str(error))


if __name__ == "__main__":
    main()
