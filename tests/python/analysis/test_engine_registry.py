"""One class per effect: the registry holds every effect of the contract
once, and the engine (diagnose, fitting, report, scoring) never tests an
effect by its name."""

from __future__ import annotations

import os
import re

import pytest
from analysis_helpers import CONTRACT_EFFECTS, REPO, RESERVED_EFFECTS

from gearsim.analysis import EFFECT_NAMES, EFFECTS
from gearsim.analysis.effects import Effect, get_effect
from gearsim.analysis.errors import EffectError

ANALYSIS = os.path.join(REPO, "bindings", "python", "gearsim", "analysis")
ENGINE = (
    "diagnose.py",
    "fitting.py",
    "report.py",
    "scoring.py",
    "identifiability.py",
    "simulate.py",
    "signatures.py",
)


def _subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _subclasses(sub)


def test_every_contract_effect_has_exactly_one_class():
    assert EFFECT_NAMES == CONTRACT_EFFECTS
    classes = list(_subclasses(Effect))
    for name in CONTRACT_EFFECTS:
        owners = [c for c in classes if c.name == name]
        assert len(owners) == 1, (name, owners)
        assert isinstance(EFFECTS[name], owners[0])
    for name in RESERVED_EFFECTS:
        assert name not in EFFECTS
        with pytest.raises(EffectError, match="unknown effect"):
            get_effect(name)
    with pytest.raises(EffectError, match="unknown effect"):
        get_effect("backlash_of_the_mind")


def test_every_class_says_what_separates_it():
    for eff in EFFECTS.values():
        assert eff.signature_text and eff.summary and eff.excitation, eff.name


@pytest.mark.parametrize("filename", ENGINE)
def test_no_effect_name_tests_in_the_engine(filename):
    with open(os.path.join(ANALYSIS, filename), encoding="utf-8") as f:
        source = f.read()
    names = "|".join(CONTRACT_EFFECTS)
    found = re.findall(rf"[\"']({names})[\"']", source)
    assert found == [], f"{filename} names effects: {found}"
