# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""Fixtures of the Python package's tests: the shipped demo scene prepared
once per session (skipped where fascia was built without prep)."""
import os
import pathlib

import pytest

import fascia

ROOT = pathlib.Path(__file__).resolve().parents[3]
DEMO = ROOT / "data" / "scenes" / "pelvis-female-demo.json"


@pytest.fixture(scope="session")
def demo_model(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "demo.h5"
    try:
        summary = fascia.prep(DEMO, out)
    except fascia.Error as e:
        if "prep" in str(e) and ("not built" in str(e) or "without" in str(e) or "no 'fascia'" in str(e)):
            pytest.skip(f"no prep here: {e}")
        raise
    assert summary["frames"] > 0 and os.path.exists(out)
    return out
