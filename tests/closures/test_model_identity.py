"""ChuteModel as the one carrier of the closure choices: registries, to_dict/from_dict, ==/hash, key.

Numbers here are identities of the definitions (a scaled g0 is the scaled Lun–Savage g0 of
paper §2.1), not physics results.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from chuteflow.closures import (
    CLOSURES,
    FIELDS,
    RADIALS,
    TRANSPORTS,
    WALLS,
    CarnahanStarling,
    ChuteModel,
    JohnsonJackson,
    LunClosure,
    LunSavage,
    RadialDistribution,
    Registry,
    register_radial,
)
from chuteflow.errors import ParameterError


@dataclass(frozen=True)
class ScaledLunSavage(RadialDistribution):
    """A closure with a parameter: ``scale`` times the Lun–Savage g0 (a test closure)."""

    name: ClassVar[str] = "test_scaled_lun_savage"
    scale: float = 1.0

    def expr(self, nu, nu_max):
        return self.scale * LunSavage().expr(nu, nu_max)


@pytest.fixture
def scaled():
    register_radial(ScaledLunSavage)
    yield ScaledLunSavage
    RADIALS.unregister(ScaledLunSavage.name)


def test_registries_hold_the_builtin_closures():
    assert set(RADIALS.names()) >= {"lun_savage", "carnahan_starling"}
    assert WALLS.names() == ("johnson_jackson",)
    assert TRANSPORTS.names() == ("garzo_dufty", "garzo_dufty_mfix", "lun", "lun_full", "lun_mfix")
    assert CLOSURES == {"radial": RADIALS, "wall": WALLS, "transport": TRANSPORTS}
    assert isinstance(RADIALS.create("carnahan_starling"), CarnahanStarling)
    assert RADIALS.spec(CarnahanStarling()) == "carnahan_starling"
    with pytest.raises(ParameterError, match="lun_savage"):
        RADIALS.create("no_such_g0")  # the message lists the choices


def test_registry_refuses_bad_classes():
    reg = Registry("radial", RadialDistribution)

    class NotADataclass(RadialDistribution):
        name: ClassVar[str] = "x"

    with pytest.raises(TypeError, match="must be a frozen dataclass"):
        reg.register(NotADataclass)
    with pytest.raises(TypeError, match="subclass"):
        reg.register(JohnsonJackson)
    reg.register(LunSavage)

    @dataclass(frozen=True)
    class Impostor(RadialDistribution):
        name: ClassVar[str] = "lun_savage"

    with pytest.raises(ValueError, match="taken"):
        reg.register(Impostor)


def test_a_new_closure_is_one_class_and_a_registration(scaled):
    """Registered, it is usable by name everywhere, and its parameters round-trip."""
    m = ChuteModel(radial={"name": "test_scaled_lun_savage", "scale": 2.0})
    assert m.radial == scaled(2.0)
    assert m.to_dict()["radial"] == {"name": "test_scaled_lun_savage", "scale": 2.0}
    assert ChuteModel.from_dict(json.loads(json.dumps(m.to_dict()))) == m
    assert ChuteModel.from_dict(m.attrs()) == m  # NetCDF form: the dict as JSON text
    nu = np.array([0.05, 0.2, 0.4])
    g_ls = ChuteModel().g0(nu)[0]
    np.testing.assert_allclose(m.g0(nu)[0], 2.0 * g_ls, rtol=1e-14)
    np.testing.assert_allclose(ChuteModel(radial="test_scaled_lun_savage").g0(nu)[0], g_ls, rtol=1e-14)
    assert m != ChuteModel(radial=scaled(3.0))
    assert m.key() != ChuteModel(radial=scaled(3.0)).key()


def test_fields_accept_names_or_instances():
    a = ChuteModel(radial="carnahan_starling", wall="johnson_jackson", transport="lun")
    b = ChuteModel(radial=CarnahanStarling(), wall=JohnsonJackson(), transport=LunClosure())
    assert a == b
    assert hash(a) == hash(b)
    assert a.key() == b.key()
    assert a.closures == (LunClosure(), CarnahanStarling(), JohnsonJackson())
    with pytest.raises(ParameterError, match="wall"):
        ChuteModel(wall="no_such_wall")
    with pytest.raises(ParameterError, match="transport"):
        ChuteModel(transport=3)


@pytest.mark.parametrize(
    "model",
    [
        ChuteModel(),
        ChuteModel(radial="carnahan_starling"),
        ChuteModel(restitution=0.95, nu_max=0.64, roughness=0.1, wall_loss=0.2),
    ],
)
def test_to_dict_from_dict_round_trip(model):
    d = model.to_dict()
    assert tuple(d) == FIELDS
    back = ChuteModel.from_dict(json.loads(json.dumps(d)))
    assert back == model
    assert hash(back) == hash(model)
    assert back.key() == model.key()
    assert model.as_dict() == d  # the older name
    assert ChuteModel.from_dict(model.attrs()) == model


def test_from_dict_defaults_and_unknown_fields():
    assert ChuteModel.from_dict({"roughness": 0.1}) == ChuteModel(roughness=0.1)
    with pytest.raises(ParameterError, match="unknown fields"):
        ChuteModel.from_dict({"roughnes": 0.1})


def test_equality_and_hash():
    ls, cs = ChuteModel(), ChuteModel(radial="carnahan_starling")
    assert ls == ChuteModel()
    assert hash(ls) == hash(ChuteModel())
    assert ls != cs
    assert hash(ls) != hash(cs)
    assert ls != ChuteModel(roughness=0.1)
    assert hash(ls) != hash(ChuteModel(roughness=0.1))
    assert ChuteModel(restitution=1) == ChuteModel(restitution=1.0)  # ints become floats
    assert len({ls, cs, ChuteModel(), ChuteModel(radial=CarnahanStarling())}) == 2


def test_key_is_stable():
    """The key is a function of the to_dict content only (here pinned: changing it
    invalidates every cache keyed by it)."""
    assert ChuteModel().key() == "e8d050ed2556654a"
    assert ChuteModel(radial="carnahan_starling").key() == "b4728a368abf3ed0"
    assert len({ChuteModel(roughness=r).key() for r in (0.05, 0.1, 0.05000001)}) == 3


def test_describe_names_non_default_closures():
    assert ChuteModel().describe() == "φ = 0.05, Φ = 0.39, e_p = 0.7, ν_m = 0.6"
    assert ChuteModel(radial="carnahan_starling").describe().endswith("radial carnahan_starling")
