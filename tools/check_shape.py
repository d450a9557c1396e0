#!/usr/bin/env python3
"""check_shape.py - rules of the source tree's shape that a compiler does not check.

Rules (docs/architecture.md, "Memory" and "Layers"):
  allocation  the library (src/) allocates only through core/alloc.h: no malloc, calloc,
              realloc or strdup outside src/core/alloc.c, and free() only for what libc
              allocated, on a line whose comment says so ("from malloc").
  layers      a folder of src/ includes headers of its own layer or lower ones (LAYERS, low
              to high), and the public headers (mpm/); the known exceptions (KNOWN_UPWARD)
              are listed with what removes them, and a new one fails.

Usage: tools/check_shape.py [--root DIR]   exit 0 when every rule holds, 1 with the violations
       tools/check_shape.py --self-test    plants a violation of each rule in a copy and checks
                                           that it is found
"""
import argparse
import os
import re
import shutil
import sys
import tempfile

ALLOC = re.compile(r'(?<![\w.>])(malloc|calloc|realloc|strdup|strndup)\s*\(')
FREE = re.compile(r'(?<![\w.>])free\s*\(')
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/([\w.]+)"')

# src/'s folders from low to high; a folder includes its own layer and the ones below
LAYERS = [
    ['core'],
    ['interp', 'grid'],
    ['material', 'collide'],
    ['transfer'],
    ['domain'],
    ['heat'],
    ['io'],
    ['scene'],
    ['adaptive'],
    ['surface'],
    ['solver'],
    ['sim'],
    ['dist'],
    ['analysis', 'plot', 'render'],
]
# upward includes that stand today, each to go (none now; the list may only shrink)
KNOWN_UPWARD = set()


def layer_of(folder):
    for k, names in enumerate(LAYERS):
        if folder in names:
            return k
    return None


def check_layers(root):
    problems = []
    seen = set()
    src = os.path.join(root, 'src')
    for folder, _, files in sorted(os.walk(src)):
        for name in sorted(files):
            if not name.endswith(('.c', '.h', '.cpp')):
                continue
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, root).replace(os.sep, '/')
            own = rel.split('/')[1]
            own_layer = layer_of(own)
            with open(path, encoding='utf-8', errors='replace') as f:
                for no, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m or m.group(1) == 'mpm':
                        continue
                    target = m.group(1)
                    if own_layer is None or layer_of(target) is None:
                        problems.append('%s:%d: a folder the layers do not list (%s or %s): '
                                        'add it to LAYERS' % (rel, no, own, target))
                        continue
                    header = '%s/%s' % (target, m.group(2))
                    if (rel, header) in KNOWN_UPWARD:
                        seen.add((rel, header))
                    elif layer_of(target) > own_layer:
                        problems.append('%s:%d: %s includes %s, a higher layer (%s over %s)'
                                        % (rel, no, own, header, target, own))
    for rel, header in sorted(KNOWN_UPWARD - seen):  # the list stays true
        problems.append('%s: no longer includes %s: take it off KNOWN_UPWARD' % (rel, header))
    return problems


def strip_comments_and_strings(line):
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])*'", "''", line)
    line = re.sub(r'/\*.*?\*/', '', line)
    return line.split('//')[0]


def check_allocation(root):
    problems = []
    src = os.path.join(root, 'src')
    for folder, _, files in sorted(os.walk(src)):
        for name in sorted(files):
            if not name.endswith(('.c', '.h')):
                continue
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, root)
            if rel == os.path.join('src', 'core', 'alloc.c'):
                continue
            in_comment = False
            with open(path, encoding='utf-8', errors='replace') as f:
                for no, raw in enumerate(f, 1):
                    line = raw
                    if in_comment:
                        if '*/' not in line:
                            continue
                        line = line.split('*/', 1)[1]
                        in_comment = False
                    code = strip_comments_and_strings(line)
                    if '/*' in code:
                        code = code.split('/*', 1)[0]
                        in_comment = '*/' not in line.split('/*', 1)[1]
                    if ALLOC.search(code):
                        problems.append('%s:%d: allocation outside core/alloc.h: %s'
                                        % (rel, no, raw.strip()))
                    if FREE.search(code):
                        if 'from malloc' not in raw:
                            problems.append('%s:%d: free() of the library\'s memory (mpm_free; '
                                            'or say "from malloc" when libc allocated it): %s'
                                            % (rel, no, raw.strip()))
    return problems


def run(root):
    return check_allocation(root) + check_layers(root)


def self_test(root):
    """Plant one violation per rule in a copy of src/ and expect each to be found."""
    plants = {
        'malloc': 'void *planted(void) { return malloc(8); }\n',
        'free': 'void planted_free(void *p) { free(p); }\n',
        'upward include': '#include "sim/sim.h"\n',
    }
    ok = True
    for rule, code in plants.items():
        with tempfile.TemporaryDirectory() as tmp:
            shutil.copytree(os.path.join(root, 'src'), os.path.join(tmp, 'src'))
            with open(os.path.join(tmp, 'src', 'core', 'planted.c'), 'w') as f:
                f.write(code)
            found = [p for p in run(tmp) if 'planted.c' in p]
            print('self-test, a planted %s: %s' % (rule, 'found' if found else 'NOT FOUND'))
            ok &= bool(found)
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--root', default=os.path.join(os.path.dirname(__file__), '..'))
    ap.add_argument('--self-test', action='store_true')
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    if args.self_test:
        return 0 if self_test(root) else 1
    problems = run(root)
    for p in problems:
        print(p)
    print('check_shape: %d violation%s' % (len(problems), '' if len(problems) == 1 else 's'))
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
