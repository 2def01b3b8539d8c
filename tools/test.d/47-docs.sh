#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/47-docs.sh - the documentation as a product (tools/docs/):
#
#   1. the words check: no tracked file names how the project was worked on
#      (tools/docs/check_words.py), after its own test on files that hold each
#      banned word and their legitimate neighbours;
#   2. the link check: every relative link and heading anchor of the tracked
#      Markdown resolves (tools/docs/check_links.py), after its own test;
#   3. the command-line reference docs/cli/ is what this build's `trn` writes
#      from its option tables (tools/docs/gen_cli_reference.py --check; needs
#      the host-release build, made by tools/test.sh before this stage);
#   4. the API reference: `cmake --build --preset host --target docs`
#      (Doxygen over include/trn/ and the modules' notes; warnings are errors).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh docs

python3 -m unittest discover -s tools/docs -p 'test_check_*.py' 2>&1 | tail -n 3
python3 tools/docs/check_words.py
python3 tools/docs/check_links.py
python3 tools/docs/gen_cli_reference.py --trn build/host-release/trn --check
cmake --preset host >/dev/null
cmake --build --preset host --target docs
echo "47-docs: words, links, command-line reference and API reference ok"
