#!/usr/bin/env python3
"""The docs runner on made-up pages: a failing block and a number off its tolerance fail with the
page and line, an unmarked shell block fails the check, the small variant and expects work."""
import os
import subprocess
import sys
import tempfile
import unittest

RUNNER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "run_docs.py")


def page(tmp, name, text):
    path = os.path.join(tmp, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    open(path, "w").write(text)


def run(tmp, *args):
    p = subprocess.run([sys.executable, RUNNER, "--source", tmp, "--bin", tmp, *args], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True)
    return p.returncode, p.stdout


class RunDocs(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        os.makedirs(os.path.join(self.tmp, "data"))
        page(self.tmp, "README.md", "# r\n")

    def test_failing_block_names_page_and_line(self):
        page(self.tmp, "docs/a.md", "# a\n\n<!-- doc-test: run -->\n```sh\necho ok\nexit 7\n```\n")
        rc, out = run(self.tmp, "docs/a.md")
        self.assertEqual(rc, 1)
        self.assertIn("docs/a.md:4: the block failed (exit 7)", out)

    def test_number_off_its_tolerance_fails_and_within_passes(self):
        text = ("<!-- doc-test: run small: '2.5' -> '2.05' -->\n"
                "<!-- doc-test: expect out.json:r[1].x = 2 ± 5% -->\n"
                "<!-- doc-test: expect output /y = (\\S+)/ = 3 ± 0.01 -->\n"
                "```sh\necho '{\"r\": [0, {\"x\": 2.5}]}' > out.json\necho y = 3.001\n```\n")
        page(self.tmp, "docs/b.md", text)
        rc, out = run(self.tmp, "docs/b.md")
        self.assertEqual(rc, 0, out)
        self.assertIn("1 blocks run, 2 numbers compared", out)
        page(self.tmp, "docs/b.md", text.replace("= 3 ± 0.01", "= 3.1 ± 0.01"))
        rc, out = run(self.tmp, "docs/b.md")
        self.assertEqual(rc, 1)
        self.assertIn("docs/b.md:3: expect output", out)

    def test_unmarked_shell_block_fails_the_check(self):
        page(self.tmp, "docs/c.md", "```yaml\na: 1\n```\n<!-- doc-test: skip: a listing -->\n```\nx\n```\n\n```sh\nls\n```\n")
        rc, out = run(self.tmp, "--check")
        self.assertEqual(rc, 1)
        self.assertIn("docs/c.md:9: shell block without a doc-test marker", out)
        self.assertIn("2 shell blocks: 0 run here", out)

    def test_shipped_file_must_match(self):
        page(self.tmp, "docs/examples/x.yaml", "a: 1\n")
        page(self.tmp, "docs/d.md", "<!-- doc-test: shipped docs/examples/x.yaml -->\n```yaml\na: 2\n```\n")
        rc, out = run(self.tmp, "docs/d.md")
        self.assertEqual(rc, 1)
        self.assertIn("docs/d.md:2: the block differs from the shipped docs/examples/x.yaml", out)


if __name__ == "__main__":
    unittest.main()
