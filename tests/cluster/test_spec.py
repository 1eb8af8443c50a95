"""The ``--cluster`` value is read without Dask and refused in one line when malformed."""

from __future__ import annotations

import subprocess
import sys

import pytest

from povagent.cluster.spec import ClusterSpec, parse_cluster_spec
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


def test_reading_a_spec_does_not_import_dask() -> None:
    code = "import sys; from povagent.cluster import parse_cluster_spec; parse_cluster_spec('local:2'); print('distributed' in sys.modules, 'dask' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]
