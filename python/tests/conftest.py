"""What the package's tests share: the `vlab` command to compare with."""

import os

import pytest


@pytest.fixture(scope="session")
def cli():
    """The vlab binary cargo built beside the package (python/tests/suite/package.rs
    sets VLAB); a test that compares with it skips without it."""
    path = os.environ.get("VLAB")
    if not path:
        pytest.skip("VLAB, the vlab binary, is set by python/tests/suite/package.rs")
    return path
