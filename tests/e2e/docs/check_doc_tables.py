#!/usr/bin/env python3
"""A results page's tables are its report's numbers: every table row that a tools/scripts table
printer prints from the committed report must be on the page verbatim (a re-run that is not
written into the page fails here).
  check_doc_tables.py SOURCE SCRIPT REPORT_DIR PAGE MIN_ROWS [SECTION ...]
SECTION: the printer's '## ' headings whose rows are checked (default: all)."""
import subprocess, sys
source, script, report, page_path, min_rows, *sections = sys.argv[1:]
out = subprocess.run([sys.executable, f'{source}/{script}', f'{source}/{report}'],
                     capture_output=True, text=True, check=True).stdout
page = open(f'{source}/{page_path}', encoding='utf-8').read()
missing, checked, section = [], 0, ''
for line in out.splitlines():
    if line.startswith('## '):
        section = line[3:]
    elif line.startswith('| ') and (not sections or section in sections):
        checked += 1
        if line not in page:
            missing.append(line)
print(f'{checked} table rows checked, {len(missing)} missing from {page_path}')
for m in missing:
    print('  missing:', m)
sys.exit(1 if missing or checked < int(min_rows) else 0)
