#!/usr/bin/env python3
"""Regenerates server/dashboard.c from server/dashboard.html (the file to edit).

Run from the repository root:  python3 server/dashboard_gen.py
tests/server/test_dashboard.c fails when dashboard.c and dashboard.html differ.
"""
import os

here = os.path.dirname(os.path.abspath(__file__))
src = open(os.path.join(here, 'dashboard.html'), 'rb').read()
out = ['/* dashboard.c -- the dashboard page served at GET / (see dashboard.h).\n',
       ' *\n',
       ' * GENERATED from server/dashboard.html by server/dashboard_gen.py: edit the HTML, then run\n',
       ' *   python3 server/dashboard_gen.py\n',
       ' * (tests/server/test_dashboard.c fails when the two differ). */\n',
       '#include "dashboard.h"\n\nstatic const char page[] =\n']
lines = src.split(b'\n')
if src.endswith(b'\n'):
    lines = lines[:-1]
for line in lines:
    s = ''
    for b in line + b'\n':
        c = chr(b)
        if c == '\\':
            s += '\\\\'
        elif c == '"':
            s += '\\"'
        elif c == '?':
            s += '\\?'  # no trigraphs
        elif c == '\n':
            s += '\\n'
        elif c == '\t':
            s += '\\t'
        elif 32 <= b < 127:
            s += c
        else:
            s += '\\%03o' % b  # octal: at most 3 digits, never swallows what follows
    out.append('    "' + s + '"\n')
out.append('    ;\n\nconst char *gp_dashboard_html(void) { return page; }\n')
open(os.path.join(here, 'dashboard.c'), 'w').write(''.join(out))
