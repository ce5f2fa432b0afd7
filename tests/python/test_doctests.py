"""The examples in the aqs package's docstrings run and print what they show."""

import doctest
import importlib

import pytest

import aqs

MODULES = ["aqs", "aqs._lib", "aqs._errors", "aqs.urdf"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = [t for t in finder.find(module, name) if t.examples]
    for test in tests:
        runner.run(test)
    results = runner.summarize(verbose=False)
    assert results.failed == 0, "%d of %d docstring examples of %s failed (output above)" % (
        results.failed, results.attempted, name)


def test_the_module_docstring_has_examples():
    # The package's own docstring and Linkage's carry runnable examples.
    finder = doctest.DocTestFinder()
    names = {t.name for t in finder.find(aqs, "aqs") if t.examples}
    assert {"aqs", "aqs.Linkage"} <= names, names
