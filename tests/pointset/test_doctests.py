"""The docstring examples of hammesh.pointset run."""

import doctest

import pytest

from hammesh import pointset
from hammesh.pointset import hamiltonian, no_sequential, sequential, sequential_few_interior, sequential_search


@pytest.mark.parametrize("module", [pointset, hamiltonian, sequential, sequential_few_interior, sequential_search,
                                    no_sequential])
def test_doctests(module):
    result = doctest.testmod(module, raise_on_error=False)
    assert result.failed == 0
