"""The docstring examples of hammesh.pointset run."""

import doctest

import pytest

from hammesh import pointset
from hammesh.pointset import lemma42_sequential, sequential_search, thm31_hamiltonian, thm41_example


@pytest.mark.parametrize("module", [pointset, thm31_hamiltonian, lemma42_sequential, sequential_search, thm41_example])
def test_doctests(module):
    result = doctest.testmod(module, raise_on_error=False)
    assert result.failed == 0
