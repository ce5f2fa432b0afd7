#!/usr/bin/env python3
"""check_layers.py -- every call in the library goes down a layer (docs/design.md).

    check_layers.py [--layers src/LAYERS] [--src src] [--objdir build/obj]

Reads the rule from LAYERS (its header says the format), maps every global symbol that an
object of OBJDIR (OBJDIR/LAYER/FILE.o for SRC/LAYER/FILE.c) defines to that object, and
for every undefined symbol of an object that another object of the library defines,
checks that the callee is in a lower layer or is a sibling the caller lists. Also: every
SRC/*/*.c is listed once and built, every line names a layer of "layers:" and siblings
above it in its own layer, and the public aqs_ functions are defined in the top layer
only. Symbols defined outside the library (libc, libccd, expat) are not calls between
layers. Calls to static inline functions of headers leave no symbol and are not seen.

Prints one line per violation, naming the file, the symbol and where it is defined, and
exits 1; else one summary line and exit 0. NM (environment) overrides the nm program.
"""

import argparse
import glob
import os
import subprocess
import sys


def parse_layers(path):
    """(layers, files, errors): layers in order; files maps "layer/file" to
    (line number, set of listed siblings) in file order."""
    layers, files, errors = None, {}, []
    with open(path) as f:
        for number, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            where = "%s:%d" % (path, number)
            if line.startswith("layers:"):
                if layers is not None:
                    errors.append("%s: a second 'layers:' line" % where)
                layers = line.split(":", 1)[1].split()
                continue
            if layers is None:
                errors.append("%s: '%s' before the 'layers:' line" % (where, line))
                continue
            name, *siblings = line.split()
            layer, _, base = name.partition("/")
            if layer not in layers or not base or "/" in base:
                errors.append("%s: %s is not LAYER/FILE with LAYER one of %s"
                              % (where, name, " ".join(layers)))
                continue
            if name in files:
                errors.append("%s: %s is listed twice" % (where, name))
                continue
            for s in siblings:
                if layer + "/" + s not in files:
                    errors.append("%s: %s lists sibling %s, which is not a file of layer %s on "
                                  "a line above it" % (where, name, s, layer))
            files[name] = (number, set(siblings))
    if layers is None:
        errors.append("%s: no 'layers:' line" % path)
        layers = []
    return layers, files, errors


def symbols(nm, obj):
    """(defined globals, undefined) of one object, from nm's POSIX format."""
    out = subprocess.run([nm, "-P", obj], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit("check_layers: %s -P %s failed: %s" % (nm, obj, out.stderr.strip()))
    defined, undefined = set(), set()
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) < 2:
            continue
        name, kind = parts[0], parts[1]
        if kind == "U":
            undefined.add(name)
        elif kind.isupper() or kind in "vw":  # globals; weak ones too
            defined.add(name)
    return defined, undefined


def check(layers_path, src, objdir, nm):
    layers, files, errors = parse_layers(layers_path)
    rank = {layer: i for i, layer in enumerate(layers)}
    sources = sorted(os.path.relpath(p, src)[:-2] for p in glob.glob(os.path.join(src, "*", "*.c")))
    for name in sources:
        if name not in files:
            errors.append("%s: src file %s/%s.c is not listed" % (layers_path, src, name))
    for name in files:
        if name not in sources:
            errors.append("%s: %s is listed but %s/%s.c does not exist" % (layers_path, name, src, name))
    owner, undefined = {}, {}
    for name in files:
        if name not in sources:
            continue
        obj = os.path.join(objdir, name + ".o")
        if not os.path.isfile(obj):
            errors.append("%s (from %s/%s.c) is not built" % (obj, src, name))
            continue
        defined, undefined[name] = symbols(nm, obj)
        for sym in defined:
            owner.setdefault(sym, name)
            if sym.startswith("aqs_") and layers and name.split("/")[0] != layers[-1]:
                errors.append("%s/%s.c defines the public function %s outside the top layer %s"
                              % (src, name, sym, layers[-1]))
    calls = 0
    for name in sorted(undefined):
        layer, base = name.split("/")
        siblings = files[name][1]
        for sym in sorted(undefined[name]):
            target = owner.get(sym)
            if target is None or target == name:
                continue
            calls += 1
            tlayer, tbase = target.split("/")
            if rank[tlayer] < rank[layer] or (tlayer == layer and tbase in siblings):
                continue
            if rank[tlayer] > rank[layer]:
                why = "layer %s is above %s" % (tlayer, layer)
            else:
                why = "sibling %s is not listed for %s in %s" % (tbase, name, layers_path)
            errors.append("%s/%s.c calls %s, defined in %s/%s.c: %s"
                          % (src, name, sym, src, target, why))
    return errors, len(files), calls


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--layers", default="src/LAYERS")
    ap.add_argument("--src", default="src")
    ap.add_argument("--objdir", default="build/obj")
    args = ap.parse_args()
    errors, nfiles, calls = check(args.layers, args.src, args.objdir, os.environ.get("NM", "nm"))
    for e in errors:
        print("check_layers: " + e)
    if errors:
        print("check_layers: %d violation(s) of %s" % (len(errors), args.layers))
        return 1
    print("check_layers: %d files, %d symbol references between them, all downward or to "
          "listed siblings (%s)" % (nfiles, calls, args.layers))
    return 0


if __name__ == "__main__":
    sys.exit(main())
