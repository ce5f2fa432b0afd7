"""pytest configuration of the aqs bindings suite.

Run (what `make check-python` does):
    cd tests/python && AQS_LIBRARY=/abs/build/libaqs.so.X.Y.Z AQS_VECTORS=/abs/tests/vectors \
        PYTHONPATH=/abs/bindings/python python3 -m pytest -q -p no:cacheprovider .
"""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)


def pytest_report_header(config):
    import aqs
    return ["aqs bindings %s from %s" % (aqs.__version__, os.path.dirname(aqs.__file__)),
            "libaqs %s from %s" % (aqs.version(), aqs.library_path),
            "vectors: %s" % (os.environ.get("AQS_VECTORS") or "(default)")]
