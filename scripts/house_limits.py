#!/usr/bin/env python3
"""The house's size limits, checked against the code.

- app/ (the executable: option tables and wiring) stays under 2,000 lines.
- No function in lib/ or app/ is longer than 150 lines or takes more than
  8 parameters, except those named in scripts/house_limits.allow, each with
  its size now as its ceiling: an entry may only shrink or go (an entry
  that no longer exceeds, or is above its function's size, is printed as
  a note to lower or remove it). Tables of data (an initialiser, not a
  function body) are not functions and are not counted.

Usage: scripts/house_limits.py [SOURCE_DIR]       check; one line per finding
       scripts/house_limits.py --list [SOURCE_DIR] every offender, as allow rows
Exit 0: the limits hold."""
import os, re, sys

APP_MAX_LINES = 2000
FN_MAX_LINES = 150
FN_MAX_PARAMS = 8
CONTROL = {'if', 'for', 'while', 'switch', 'catch', 'return', 'sizeof', 'do', 'else'}


def strip(text):
    """Comments, strings and character literals blanked (newlines kept),
    preprocessor lines blanked, so braces and parentheses are code."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i)); i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j])); i = j
        elif c in '"\'':
            m = re.match(r'R"([^(\s]*)\(', text[i - 1:i + 20]) if i and text[i - 1] == 'R' and c == '"' else None
            if m:
                end = text.find(')' + m.group(1) + '"', i)
                j = n if end < 0 else end + len(m.group(1)) + 2
            else:
                j = i + 1
                while j < n and text[j] != c and text[j] != '\n':
                    j += 2 if text[j] == '\\' else 1
                j = min(j + 1, n)
            out.append(c + re.sub(r'[^\n]', ' ', text[i + 1:j - 1]) + (c if j - 1 > i else '')); i = j
        elif c == '#' and (i == 0 or text[text.rfind('\n', 0, i) + 1:i].strip() == ''):
            j = i
            while True:  # a directive with its continuation lines
                k = text.find('\n', j)
                if k < 0: k = n; break
                if text[k - 1] != '\\': break
                j = k + 1
            out.append(re.sub(r'[^\n]', ' ', text[i:k])); i = k
        else:
            out.append(c); i += 1
    return ''.join(out)


def header_of(code, start):
    """The text before a '{' back to the previous ';', '{' or '}'."""
    j = start - 1
    depth = 0
    while j >= 0:
        ch = code[j]
        if ch == ')': depth += 1
        elif ch == '(': depth -= 1
        elif depth == 0 and ch in ';{}': break
        j -= 1
    return j + 1, code[j + 1:start]


def function_name_and_params(head):
    """(name, parameter count) when head is a function definition's header,
    else None."""
    h = head.strip()
    if not h or '=' in re.sub(r'operator\s*\S+', '', h.split('(')[0]):
        return None
    # C++: trailing qualifiers and a constructor's initialiser list.
    h = re.sub(r'\)\s*(const|override|noexcept|final|\s)*(->[^{]*)?$', ')', h)
    m = None
    depth = 0
    # the parameter list: the first top-level (...) after the name
    for k, ch in enumerate(h):
        if ch == '(':
            if depth == 0 and m is None:
                m = k
            depth += 1
        elif ch == ')':
            depth -= 1
            if depth == 0 and m is not None:
                close = k
                break
    else:
        return None
    rest = h[close + 1:].strip()
    if rest and not rest.startswith(':'):
        return None
    before = h[:m].strip()
    nm = re.search(r'(~?[A-Za-z_]\w*(?:::~?[A-Za-z_]\w*)*|operator\s*\S+)\s*$', before)
    if not nm or nm.group(1) in CONTROL or before.endswith(']'):
        return None
    if not re.search(r'[\w*&>]\s', before) and '::' not in nm.group(1):
        return None  # a call or a macro, not a definition (no return type)
    if re.match(r'(struct|union|enum|class|namespace|typedef)\b', before):
        return None
    params = h[m + 1:close].strip()
    count = 0
    if params and params != 'void':
        depth = 0
        count = 1
        for ch in params:
            if ch in '(<[': depth += 1
            elif ch in ')>]': depth -= 1
            elif ch == ',' and depth == 0: count += 1
    return nm.group(1), count


def functions(path):
    """(name, first line, lines, parameters) of each function defined in path."""
    text = open(path, encoding='utf-8', errors='replace').read()
    code = strip(text)
    found = []
    i, n = 0, len(code)
    while i < n:
        if code[i] == '{':
            hs, head = header_of(code, i)
            fn = function_name_and_params(head)
            # find the matching brace
            depth, j = 0, i
            while j < n:
                if code[j] == '{': depth += 1
                elif code[j] == '}':
                    depth -= 1
                    if depth == 0: break
                j += 1
            if fn:
                first = code.count('\n', 0, hs + len(head) - len(head.lstrip())) + 1
                last = code.count('\n', 0, j) + 1
                found.append((fn[0], first, last - first + 1, fn[1]))
                i = j + 1
                continue
        i += 1
    return found


def sources(root, folders):
    for folder in folders:
        for dp, _, names in os.walk(os.path.join(root, folder)):
            for name in sorted(names):
                if name.endswith(('.c', '.cc', '.h')):
                    yield os.path.join(dp, name)


def main(argv):
    listing = '--list' in argv
    args = [a for a in argv[1:] if a != '--list']
    root = os.path.abspath(args[0] if args else os.path.join(os.path.dirname(__file__), '..'))
    bad = []

    app_lines = sum(open(p, encoding='utf-8', errors='replace').read().count('\n') for p in sources(root, ['app']))
    if app_lines > APP_MAX_LINES:
        bad.append(f'app/: {app_lines} lines, more than {APP_MAX_LINES} (app/ is option tables and wiring: '
                   'move the logic into lib/)')

    offenders = {}
    for p in sources(root, ['lib', 'app']):
        rel = os.path.relpath(p, root)
        for name, line, length, params in functions(p):
            if length > FN_MAX_LINES:
                offenders[('lines', rel, name)] = (length, line)
            if params > FN_MAX_PARAMS:
                offenders[('params', rel, name)] = (params, line)
    if listing:
        for (kind, rel, name), (v, line) in sorted(offenders.items(), key=lambda kv: (kv[0][0], -kv[1][0])):
            print(f'{kind} {rel} {name} {v}')
        print(f'# app/ {app_lines} lines; {sum(k[0] == "lines" for k in offenders)} functions over {FN_MAX_LINES} '
              f'lines, {sum(k[0] == "params" for k in offenders)} with more than {FN_MAX_PARAMS} parameters',
              file=sys.stderr)
        return 0

    allow = {}
    allow_path = os.path.join(root, 'scripts', 'house_limits.allow')
    for k, row in enumerate(open(allow_path, encoding='utf-8').read().splitlines(), 1):
        row = row.split('#')[0].split()
        if not row:
            continue
        if len(row) != 4 or row[0] not in ('lines', 'params') or not row[3].isdigit():
            bad.append(f'scripts/house_limits.allow:{k}: want "lines|params FILE FUNCTION N"')
            continue
        allow[(row[0], row[1], row[2])] = int(row[3])

    for key, (v, line) in sorted(offenders.items()):
        kind, rel, name = key
        what = f'{v} lines' if kind == 'lines' else f'{v} parameters'
        limit = FN_MAX_LINES if kind == 'lines' else FN_MAX_PARAMS
        if key not in allow:
            bad.append(f'{rel}:{line}: {name} has {what} (the limit is {limit}): split it '
                       '(named steps, a params struct)')
        elif v > allow[key]:
            bad.append(f'{rel}:{line}: {name} grew to {what} (scripts/house_limits.allow holds it at {allow[key]})')
    # A row that is no longer needed, or higher than its function, is a
    # note to lower or remove it, not a failure: work that shrinks a
    # function must not turn the check red for everyone.
    notes = []
    for key, v in sorted(allow.items()):
        if key not in offenders:
            notes.append(f'scripts/house_limits.allow: "{" ".join(key)}" is within the limit now (or gone): '
                       'remove the row')
        elif offenders[key][0] < v:
            notes.append(f'scripts/house_limits.allow: "{" ".join(key)}" is {offenders[key][0]} now: lower the row '
                       f'from {v}')
    for b in notes:
        print('note: ' + b)
    for b in bad:
        print(b)
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
