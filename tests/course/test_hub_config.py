"""deploy/jupyterhub/jupyterhub_config.py, loaded without starting a hub: what every class gets."""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace

from traitlets.config.loader import PyFileConfigLoader

from .course_support import REPO

CONFIG = REPO / "deploy" / "jupyterhub" / "jupyterhub_config.py"


def _load(tmp_path, monkeypatch, **env):
    for name, value in {"MT_HUB_STATE": str(tmp_path / "state"), **env}.items():
        monkeypatch.setenv(name, value)
    return PyFileConfigLoader(CONFIG.name, path=str(CONFIG.parent)).load_config()


def test_the_hub_listens_on_loopback_only_with_the_dummy_authenticator(tmp_path, monkeypatch):
    config = _load(tmp_path, monkeypatch, MT_HUB_PORT="8123")
    assert config.JupyterHub.ip == config.JupyterHub.hub_ip == "127.0.0.1"
    assert config.ConfigurableHTTPProxy.api_url.startswith("http://127.0.0.1:")
    assert config.JupyterHub.port == 8123
    assert config.JupyterHub.authenticator_class == "dummy"
    assert config.JupyterHub.spawner_class == "simple"
    assert ("--allow-root" in config.Spawner.args) == (os.geteuid() == 0)


def test_each_student_gets_their_own_numba_cache_and_nothing_writes_into_the_install(tmp_path, monkeypatch):
    config = _load(tmp_path, monkeypatch, MT_WIDGETS_CLASS_FOLDER="/srv/class", MT_WIDGETS_EXCHANGE="/srv/exchange")
    environment = config.Spawner.environment
    spawner = SimpleNamespace(home_dir=str(tmp_path / "homes" / "ada"), user=SimpleNamespace(name="ada"), port=0)
    assert environment["NUMBA_CACHE_DIR"](spawner) == str(tmp_path / "homes" / "ada" / ".cache" / "numba")
    assert environment["PYTHONDONTWRITEBYTECODE"] == "1"
    assert environment["MT_WIDGETS_CLASS_FOLDER"] == "/srv/class"
    assert environment["MT_WIDGETS_EXCHANGE"] == "/srv/exchange"
    assert Path(environment["JUPYTER_CONFIG_PATH"], "nbgrader_config.py").is_file()


def test_the_spawn_hook_copies_a_warm_cache_once_and_picks_a_port_below_the_ephemeral_range(tmp_path, monkeypatch):
    template = tmp_path / "template"
    (template / "core_x").mkdir(parents=True)
    (template / "core_x" / "f.nbi").write_text("index")
    config = _load(tmp_path, monkeypatch, MT_HUB_NUMBA_TEMPLATE=str(template))
    spawner = SimpleNamespace(home_dir=str(tmp_path / "homes" / "ada"), user=SimpleNamespace(name="ada"), port=0)
    config.Spawner.pre_spawn_hook(spawner)
    cached = tmp_path / "homes" / "ada" / ".cache" / "numba" / "core_x" / "f.nbi"
    assert cached.read_text() == "index"
    assert 20000 <= spawner.port < 32768
    cached.write_text("the student's own")
    config.Spawner.pre_spawn_hook(spawner)  # a restart keeps the student's cache
    assert cached.read_text() == "the student's own"
