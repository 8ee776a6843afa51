#!/usr/bin/env python3
"""canopy_cut.py IN.hir OUT.hir EXPR: keeps the plants of a `hirad gen canopy` scene (exact
instances named rRpP: row R, plant P) for which EXPR (in r, p) holds; everything else as it is.

The dense 320-plant block of BENCHMARKS.md:
    hirad gen canopy -o canopy.hir
    python3 benches/canopy_cut.py canopy.hir cblock.hir "8 <= r <= 15 and 30 <= p <= 69"
    hirad convert cblock.hir -o cblock.hirb
"""
import re, sys
src, dst, expr = sys.argv[1:4]
out = []
kept = 0
for line in open(src):
    m = re.search(r'instance \S+ exact name r(\d+)p(\d+) ', line)
    if m:
        r, p = int(m.group(1)), int(m.group(2))
        if not eval(expr):
            continue
        kept += 1
    out.append(line)
open(dst, 'w').write(''.join(out))
print(kept, 'instances')
