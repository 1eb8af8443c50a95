"""The ``--cluster`` value is read without Dask and refused in one line when malformed."""

from __future__ import annotations

import subprocess
import sys

import pytest

from povagent.config.cluster_spec import ClusterSpec, local_worker_limit, parse_cluster_spec, yaml_cluster_spec
from povagent.config.sweep_models import SweepConfig
from povagent.errors import ClusterError


def test_local_names_a_number_of_worker_processes() -> None:
    assert parse_cluster_spec("local:2") == ClusterSpec(local_workers=2)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "tcp://scheduler.cluster.local:8786", "tls://[::1]:8786"])
def test_a_scheduler_address_is_kept_as_given(address: str) -> None:
    assert parse_cluster_spec(address) == ClusterSpec(address=address)


@pytest.mark.parametrize("value", ["local:0", "local:", "local:two", "local:100000", "127.0.0.1:8786", "http://x:1", "tcp://h:99999", "tcp://a b:1"])
def test_anything_else_is_refused_naming_both_forms(value: str) -> None:
    with pytest.raises(ClusterError) as info:
        parse_cluster_spec(value)
    assert "\n" not in str(info.value)
    assert repr(value) in str(info.value)


@pytest.mark.parametrize("value", ["local:\u00b2", "local:\u0663", "local:" + "9" * 5000, "local:007x"])
def test_a_local_count_is_ascii_digits_or_one_line(value: str) -> None:
    # int() of a superscript two raises ValueError, and so does int() of 5,000 digits
    with pytest.raises(ClusterError, match="local:N takes a number of worker processes") as info:
        parse_cluster_spec(value)
    assert "\n" not in str(info.value)


def test_a_local_cluster_larger_than_this_machine_allows_is_refused() -> None:
    most = local_worker_limit()
    assert parse_cluster_spec(f"local:{most}") == ClusterSpec(local_workers=most)
    with pytest.raises(ClusterError, match=f"from 1 to {most} on this machine"):
        parse_cluster_spec(f"local:{most + 1}")


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "tls://scheduler.example:8786", "inproc://x"])
def test_a_yaml_naming_a_scheduler_is_refused_naming_the_flag(address: str) -> None:
    with pytest.raises(ClusterError, match="--cluster") as info:
        yaml_cluster_spec(address)
    assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match="a YAML file may ask for local:N only"):
        SweepConfig.model_validate({"base": "b.yaml", "output": "out", "cluster": address})


def test_a_yaml_may_ask_for_a_local_cluster() -> None:
    assert yaml_cluster_spec("local:2") == ClusterSpec(local_workers=2)
    assert SweepConfig.model_validate({"base": "b.yaml", "output": "out", "cluster": "local:2"}).cluster == "local:2"


def test_reading_a_spec_does_not_import_dask() -> None:
    code = (
        "import sys; from povagent.cluster import parse_cluster_spec; parse_cluster_spec('local:2'); print('distributed' in sys.modules, 'dask' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_checking_a_config_loads_neither_the_cluster_room_nor_the_image_server() -> None:
    # configuration is data at the bottom: a pipeline with a cluster key and an image server's
    # bind is checked without importing the rooms that will act on them
    code = (
        "import sys; from povagent.config.models import ImagesSpec; from povagent.config.sweep_models import SweepConfig; "
        "ImagesSpec.model_validate({'transport': 'http', 'bind': '127.0.0.1:0'}); "
        "SweepConfig._cluster_spec('local:2'); "
        "print(*(name in sys.modules for name in ('povagent.cluster', 'povagent.exchange.image_server', 'dask')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False", "False"]
