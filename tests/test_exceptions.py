"""The error tree: every PkdynError subclass is exported from pkdyn."""

import inspect

import pytest

import pkdyn
import pkdyn.exceptions as ex


def test_every_pkdyn_error_is_exported():
    classes = [
        obj
        for _, obj in inspect.getmembers(ex, inspect.isclass)
        if issubclass(obj, ex.PkdynError) and obj.__module__ == ex.__name__
    ]
    assert len(classes) > 10
    for cls in classes:
        assert cls.__name__ in ex.__all__, f"{cls.__name__} missing from pkdyn.exceptions.__all__"
        assert cls.__name__ in pkdyn.__all__, f"{cls.__name__} missing from pkdyn.__all__"
        assert getattr(pkdyn, cls.__name__) is cls


def test_simulation_error_names_the_time():
    err = pkdyn.SimulationError("closures lost", 0.25)
    assert err.time == 0.25 and str(err) == "t = 0.25 s: closures lost"


def test_user_errors_of_maps_and_closed_forms_are_pkdyn_errors(delta):
    import numpy as np

    from pkdyn.analysis.maps import delta_map
    from pkdyn.closed_form import five_bar, planar_3rrr
    from pkdyn.plotting.maps import plot_conditioning_map

    with pytest.raises(pkdyn.InvalidInputError, match="plane"):
        delta_map(delta.params, np.zeros(2), np.zeros(2), -0.4, plane="xw")
    four = pkdyn.load("delta", arms=4, geometry=False)
    with pytest.raises(pkdyn.InvalidInputError, match="three-armed"):
        delta_map(four.params, np.zeros(2), np.zeros(2), -0.4)
    cmap = delta_map(delta.params, np.linspace(-0.05, 0.05, 2), np.zeros(1), -0.4)
    with pytest.raises(pkdyn.InvalidInputError, match="field"):
        plot_conditioning_map(cmap, field="volume")
    with pytest.raises(pkdyn.InvalidInputError, match="working_mode"):
        five_bar.mode_signs("+x")
    p3 = pkdyn.load("planar_3rrr", geometry=False).params
    with pytest.raises(pkdyn.InvalidInputError, match="pose"):
        planar_3rrr.inverse(p3, np.zeros((2, 4)))
