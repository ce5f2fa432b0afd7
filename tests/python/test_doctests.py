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


def test_bindings_readme_blocks_run_in_sequence(capsys):
    """bindings/python/README.md's Python blocks run one after the other as
    written (the second continues with the first's linkage; it was closed
    by the first block's `with`, and `j` was undefined)."""
    import os
    import re
    readme = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir,
                          "bindings", "python", "README.md")
    if not os.path.exists(readme):
        pytest.skip("no source checkout (bindings/python/README.md)")
    with open(readme, encoding="utf-8") as handle:
        blocks = re.findall(r"```python\n(.*?)```", handle.read(), re.S)
    assert len(blocks) >= 2
    namespace = {}
    for k, block in enumerate(blocks):
        exec(compile(block, "%s, Python block %d" % (readme, k + 1), "exec"), namespace)
