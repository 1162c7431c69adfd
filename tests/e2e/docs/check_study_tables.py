#!/usr/bin/env python3
"""docs/study.md's results and route tables are the report's numbers: every row that
tools/scripts/study_tables.py prints from docs/study/summary.json must be on the page verbatim
(a re-run of the study that is not written into the page fails here)."""
import subprocess, sys
source = sys.argv[1]
out = subprocess.run([sys.executable, f'{source}/tools/scripts/study_tables.py', f'{source}/docs/study'],
                     capture_output=True, text=True, check=True).stdout
page = open(f'{source}/docs/study.md', encoding='utf-8').read()
missing, checked, section = [], 0, ''
for line in out.splitlines():
    if line.startswith('## '):
        section = line
    elif section in ('## main table', '## route table (homogeneous sintered / homothetic)') and line.startswith('| '):
        checked += 1
        if line not in page:
            missing.append(line)
print(f'{checked} table rows checked, {len(missing)} missing from docs/study.md')
for m in missing:
    print('  missing:', m)
sys.exit(1 if missing or checked < 10 else 0)
