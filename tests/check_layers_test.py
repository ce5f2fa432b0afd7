#!/usr/bin/env python3
"""check_layers_test.py -- tests/check_layers.py can fail (make check-layers).

    check_layers_test.py [CC] [OBJDIR]

1. A generated two-layer library (low/, high/), compiled with CC into tiny objects, and
   maps of it: the good map passes; an upward call, an unlisted sibling, a sibling listed
   below its caller, a source file missing from the map, a listed file without source, a
   file not built, and a public aqs_ function below the top layer each fail, with a line
   naming the file, the symbol and its definition where there is one.
2. With OBJDIR (the library's build/obj): src/LAYERS with its layers in reverse order,
   and with one sibling struck from a line, fail on the real objects.
"""

import os
import re
import shlex
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import check_layers  # noqa: E402

SOURCES = {
    "low/a.c": "int a_fn(void) { return 1; }\n",
    "low/b.c": "int a_fn(void);\nint b_fn(void) { return a_fn() + 1; }\n",
    "high/c.c": "int b_fn(void);\nint aqs_c(void) { return b_fn(); }\n",
    "high/d.c": "int aqs_c(void);\nint a_fn(void);\nint d_fn(void) { return aqs_c() + a_fn(); }\n",
}
GOOD = "layers: low high\nlow/a\nlow/b a\nhigh/c\nhigh/d c\n"

failures = 0


def build(root, cc, sources):
    for name, text in sources.items():
        for top in ("src", "obj"):
            os.makedirs(os.path.join(root, top, os.path.dirname(name)), exist_ok=True)
        src = os.path.join(root, "src", name)
        with open(src, "w") as f:
            f.write(text)
        obj = os.path.join(root, "obj", name[:-2] + ".o")
        subprocess.run(shlex.split(cc) + ["-c", src, "-o", obj], check=True)


def expect(label, layers_text, root, must, layers_path=None, src=None, objdir=None):
    """Run the checker; must is None (pass) or a regex one error line must match."""
    global failures
    if layers_path is None:
        layers_path = os.path.join(root, "LAYERS")
        with open(layers_path, "w") as f:
            f.write(layers_text)
    errors, _, _ = check_layers.check(layers_path, src or os.path.join(root, "src"),
                                      objdir or os.path.join(root, "obj"),
                                      os.environ.get("NM", "nm"))
    if must is None:
        ok, shown = not errors, ""
    else:
        matched = [e for e in errors if re.search(must, e)]
        ok = bool(matched)
        shown = ": " + (matched[0] if matched else "no line matches " + must)
    print("%s %s%s" % ("ok  " if ok else "FAIL", label, shown))
    if not ok:
        failures += 1
        for e in errors:
            print("     " + e)


def main():
    cc = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("CC", "cc")
    objdir = sys.argv[2] if len(sys.argv) > 2 else None
    with tempfile.TemporaryDirectory() as root:
        build(root, cc, SOURCES)
        expect("the good map passes", GOOD, root, None)
        expect("an unlisted sibling fails", GOOD.replace("high/d c", "high/d"), root,
               r"high/d\.c calls aqs_c, defined in .*high/c\.c: sibling c is not listed")
        expect("a sibling listed below its caller fails",
               "layers: low high\nlow/b a\nlow/a\nhigh/c\nhigh/d c\n", root,
               r"low/b lists sibling a, which is not a file of layer low on a line above it")
        expect("an upward call fails (layers swapped)", "layers: high low\nlow/a\nlow/b a\nhigh/c\nhigh/d c\n",
               root, r"high/c\.c calls b_fn, defined in .*low/b\.c: layer low is above high")
        expect("a public function below the top layer fails",
               "layers: high low top\nlow/a\nlow/b a\nhigh/c\nhigh/d c\n", root,
               r"high/c\.c defines the public function aqs_c outside the top layer top")
        expect("a source file missing from the map fails", "layers: low high\nlow/a\nlow/b a\nhigh/c\n",
               root, r"src file .*high/d\.c is not listed")
        expect("a listed file without source fails", GOOD + "high/e\n", root,
               r"high/e is listed but .*high/e\.c does not exist")
        expect("a file of no layer fails", GOOD + "mid/x\n", root,
               r"mid/x is not LAYER/FILE with LAYER one of low high")
        build(root, cc, {"high/f.c": "int f_fn(void) { return 0; }\n"})
        os.remove(os.path.join(root, "obj", "high", "f.o"))
        expect("a file not built fails", GOOD + "high/f\n", root, r"high/f\.o .* is not built")
    if objdir:
        repo = os.path.dirname(HERE)
        with open(os.path.join(repo, "src", "LAYERS")) as f:
            real = f.read()
        with tempfile.TemporaryDirectory() as root:
            order = re.search(r"^layers:(.*)$", real, re.M).group(1).split()
            reverse = real.replace("layers:" + re.search(r"^layers:(.*)$", real, re.M).group(1),
                                   "layers: " + " ".join(reversed(order)))
            expect("src/LAYERS reversed fails on the library's objects", reverse, root,
                   r"calls .*: layer \w+ is above \w+", src=os.path.join(repo, "src"), objdir=objdir)
            struck = re.sub(r"^(solve/dca\s.*?)\bframes\b", r"\1", real, flags=re.M)
            assert struck != real
            expect("src/LAYERS without solve/dca's sibling frames fails on the library's objects",
                   struck, root, r"solve/dca\.c calls frames_\w+, defined in .*solve/frames\.c: "
                   r"sibling frames is not listed", src=os.path.join(repo, "src"), objdir=objdir)
    if failures:
        print("check_layers_test: %d case(s) failed" % failures)
        return 1
    print("check_layers_test: every case failed or passed as it must")
    return 0


if __name__ == "__main__":
    sys.exit(main())
