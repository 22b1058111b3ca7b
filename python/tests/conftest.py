"""Fixtures shared by the package's tests."""

from __future__ import annotations

from typing import Iterator

import pytest

import vibrofem as vf


@pytest.fixture(scope="session")
def design_report(tmp_path_factory: pytest.TempPathFactory) -> Iterator[vf.AppReport]:
    """The built-in design's report, run once (about a minute on 2 cores) for the app and browser
    tests."""
    yield vf.design(out=tmp_path_factory.mktemp("design"))
