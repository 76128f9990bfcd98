"""The shipped Voila configuration of the demo and study pages (deploy/voila/voila.py), as values.

What the values do is shown in a real Voila and Chromium by tests/browser/test_kiosk.py."""

from pathlib import Path

from traitlets.config.loader import PyFileConfigLoader

# Imported before the config is loaded: the config puts deploy/voila (holding a voila.py) on sys.path.
from voila.app import Voila

from mt_widgets.cli.servers import voila_command

REPO = Path(__file__).resolve().parents[1]
DEPLOY = REPO / "deploy" / "voila"


def shipped():
    return PyFileConfigLoader("voila.py", path=str(DEPLOY)).load_config()


def test_shipped_configuration_culls_idle_unconnected_kernels_and_preheats_only_the_two_pages():
    config = shipped()
    culler = config.MappingKernelManager
    assert culler.cull_idle_timeout >= 300, "a visitor who steps away for a few minutes must find a live page"
    assert 0 < culler.cull_interval <= culler.cull_idle_timeout / 5
    assert culler.cull_connected is False, "an open page (the kiosk's own screen) must keep its kernel"
    assert culler.cull_busy is False
    assert config.Voila.tornado_settings == {"disable_check_xsrf": True,   # the pages' shutdown beacons
                                             "static_immutable_cache": ["/voila/labextensions/"]}
    # The widgets' extensions stay; the unused ones go.
    denied = config.VoilaConfiguration.extension_denylist
    assert "@jupyter/nbgrader" in denied and "@jupyter-notebook/lab-extension" in denied
    widgets = {"@jupyter-widgets/jupyterlab-manager", "ipycanvas", "anywidget", "@voila-dashboards/widgets-manager8"}
    assert not widgets & set(denied)
    assert config.VoilaConfiguration.preheat_kernel is True
    # The server's own logger at INFO (its debug calls cost CPU on every relayed widget message),
    # under the name Voila's application logs with.
    assert Voila().log.name in config.Voila.logging_config["loggers"]
    assert config.Voila.logging_config["loggers"][Voila().log.name]["level"] == "INFO"
    # Kernels over IPC sockets (no ports to collide on when the pools start kernels together), in a
    # connection folder short enough for a socket's path (at most 107 bytes).
    assert config.KernelManager.transport == "ipc"
    assert len(f"{config.Voila.connection_dir_root}/voila_xxxxxxxx/kernel-{'0' * 36}-ipc-5") <= 107
    assert config.VoilaConfiguration.multi_kernel_manager_class == "kiosk_kernels.KioskKernelManager"
    pools = config.VoilaKernelManager.kernel_pools_config
    assert pools["default"]["pool_size"] == 0
    assert pools["demo.ipynb"]["pool_size"] == 1 and pools["study_sim.ipynb"]["pool_size"] == 1
    # The refill waits until a visitor's page is interactive (a warm visit's p95: 2.4 s measured), so
    # it does not compete with it for the 2 cores, and not much longer (the next visitor waits it out).
    assert 2.5 <= config.VoilaKernelManager.fill_delay <= 5.0
    # The README's way of serving the pages (the scripts, over `mt-widgets demo` and `mt-widgets study
    # serve`) uses this file.
    for script, command in (("serve-demo.sh", "mt_widgets.cli demo"), ("serve-study.sh", "mt_widgets.cli study serve")):
        assert command in (REPO / "scripts" / script).read_text(), script
    served = voila_command(REPO / "notebooks" / "demo.ipynb", None, [])
    assert f"--Voila.config_file_paths={REPO / 'deploy' / 'voila'}" in served


def test_the_log_leaves_out_only_the_notebook_trust_line_of_every_visit():
    import logging
    import logging.config

    config = shipped()   # puts deploy/voila on sys.path, as the server does
    logging_config = config.Voila.logging_config
    assert logging_config["loggers"][Voila().log.name]["filters"] == ["notebook_trust"]
    logging.config.dictConfig({"version": 1, "disable_existing_loggers": False,
                               "filters": logging_config["filters"],
                               "handlers": {}, "loggers": {"kiosk-test": {"filters": ["notebook_trust"]}}})
    logger = logging.getLogger("kiosk-test")
    kept = []
    logger.addHandler(type("Keep", (logging.Handler,), {"emit": lambda self, record: kept.append(record)})())
    logger.warning("Notebook %s is not trusted", "demo.ipynb")
    logger.warning("Kernel %s died", "k1")
    assert [record.getMessage() for record in kept] == ["Kernel k1 died"]
