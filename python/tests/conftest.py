"""Shared fixtures: the repository root, a registry of the embedded definitions, and the
`vstructc` command line the round-trip tests compare with."""

import os
import pathlib

import pytest

import vstructc

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def reg():
    return vstructc.Registry()


@pytest.fixture(scope="session")
def cli():
    """The `vstructc` binary: $VSTRUCTC_BIN (which must exist when set), else a build in
    target/release or target/debug; the tests that need it are skipped without one."""
    given = os.environ.get("VSTRUCTC_BIN")
    if given:
        assert pathlib.Path(given).is_file(), f"VSTRUCTC_BIN={given} does not exist"
        return given
    for profile in ("release", "debug"):
        p = REPO / "target" / profile / "vstructc"
        if p.is_file():
            return str(p)
    pytest.skip("no vstructc binary: build it with `cargo build --release`")
