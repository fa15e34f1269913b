"""The examples in hammesh.domain's docstrings run as written."""

import doctest

import pytest

from hammesh.domain import intersections, pslg, repair, resolution, triangle_files, validate


@pytest.mark.parametrize("module", [pslg, repair, resolution, intersections, triangle_files,
                                    validate], ids=lambda m: m.__name__)
def test_doctests(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
