#!/usr/bin/env python3
"""The module map in docs/architecture.md against the code.

Reads the map's table (module, header, owns, uses, hides) and fails, one
line per finding, when CMakeLists.txt links a library module to one its
row does not list under "uses", when a file of lib/X includes another
module's public header that X's row does not list, when a module of
lib/ has no row, or when the uses form a circle. Exit 0: the map holds.
Usage: scripts/check_modules.py [SOURCE_DIR]"""
import os, re, sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
doc = open(os.path.join(root, 'docs', 'architecture.md'), encoding='utf-8').read()
cmake = open(os.path.join(root, 'CMakeLists.txt'), encoding='utf-8').read()
bad = []

# The map: rows "| `lib/X` | `mr_X.h` | owns | uses | hides |".
uses = {}
for line in doc.splitlines():
    m = re.match(r'\|\s*`lib/(\w+)`\s*\|\s*`mr_\w+\.h`\s*\|[^|]*\|([^|]*)\|', line)
    if m:
        allowed = {u.strip() for u in m.group(2).split(',') if u.strip() not in ('', '—', '-')}
        uses[m.group(1)] = allowed
if not uses:
    sys.exit('check_modules: no module map found in docs/architecture.md')
for mod, allowed in uses.items():
    for u in allowed:
        if u not in uses:
            bad.append(f'map: lib/{mod} uses "{u}", which has no row')

# Every module folder has a row.
for d in sorted(os.listdir(os.path.join(root, 'lib'))):
    if os.path.isdir(os.path.join(root, 'lib', d)) and d not in uses:
        bad.append(f'map: lib/{d} has no row')

def module_of(target):
    """mr_track_cv belongs to lib/track, mr_eval_cv to lib/eval."""
    m = re.fullmatch(r'mr_(\w+?)(?:_cv)?', target)
    return m.group(1) if m and m.group(1) in uses else None

# CMake: target_link_libraries(mr_X ... mr_Y ...), the authority.
for m in re.finditer(r'target_link_libraries\(\s*(mr_\w+)([^)]*)\)', cmake):
    src = module_of(m.group(1))
    if not src:
        continue
    for dep in re.findall(r'\bmr_\w+', m.group(2)):
        d = module_of(dep)
        if d and d != src and d not in uses[src]:
            bad.append(f'CMakeLists.txt: {m.group(1)} links {dep}, but lib/{src} may use only: '
                       f'{", ".join(sorted(uses[src])) or "nothing"}')

# Sources: #include "mr_Y.h" of another module.
for mod in uses:
    folder = os.path.join(root, 'lib', mod)
    if not os.path.isdir(folder):
        continue
    for name in sorted(os.listdir(folder)):
        if not name.endswith(('.c', '.cc', '.h')):
            continue
        text = open(os.path.join(folder, name), encoding='utf-8', errors='replace').read()
        for inc in re.findall(r'#\s*include\s+"mr_(\w+)\.h"', text):
            if inc in uses and inc != mod and inc not in uses[mod]:
                bad.append(f'lib/{mod}/{name} includes mr_{inc}.h, but lib/{mod} may use only: '
                           f'{", ".join(sorted(uses[mod])) or "nothing"}')

# One way only: no circle in the map.
state = {}
def visit(m, path):
    state[m] = 1
    for u in sorted(uses.get(m, ())):
        if state.get(u) == 1:
            bad.append('map: circle ' + ' -> '.join(path + [m, u]))
        elif u in uses and not state.get(u):
            visit(u, path + [m])
    state[m] = 2
for m in sorted(uses):
    if not state.get(m):
        visit(m, [])

for b in bad:
    print('check_modules: ' + b, file=sys.stderr)
sys.exit(1 if bad else 0)
