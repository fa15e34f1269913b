"""The examples in the docstrings of hammesh.polygon run and stay true."""

import doctest
import importlib

import pytest

MODULES = ["_polygon", "visibility", "hamiltonian", "sequential", "steiner", "min_convex_ip",
           "path_partition", "_triangulate", "plot", "min_convex", "_holes", "hamiltonian_holes"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(f"hammesh.polygon.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
