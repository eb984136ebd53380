"""Every registered effect passes the shared battery of ``tests/effect_checks.py`` (issue 17)."""

import pytest
import torch

from effect_checks import check_effect, check_gradients, check_no_in_place
from synthaug.effects.registry import Effect, RenderState, list_effects


@pytest.mark.parametrize("channels", [1, 3])
@pytest.mark.parametrize("name", list_effects())
def test_registered_effect_passes_the_battery(name, channels):
    check_effect(name, channels)


class _InPlace(Effect):
    name = "_in_place"
    stage = "object"
    order = 0.0

    def apply(self, state: RenderState) -> RenderState:
        state.object_color.mul_(0.5)
        return state


class _WrongGradient(Effect):
    name = "_wrong_gradient"
    stage = "object"
    order = 0.0

    def apply(self, state: RenderState) -> RenderState:
        c = state.object_color
        return state.replace(object_color=c + (c.square() - c.square().detach()))  # value c, gradient 1 + 2c


def test_the_battery_can_fail():
    with pytest.raises(AssertionError, match="in place"):
        check_no_in_place(_InPlace())
    with pytest.raises(RuntimeError, match="Jacobian mismatch"):  # GradcheckError
        check_gradients(_WrongGradient())
