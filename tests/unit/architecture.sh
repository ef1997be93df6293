#!/usr/bin/env bash
# The architecture rules (docs/architecture.md), read from the code by
# scripts/check_architecture.py: no include circle between the folders of src/ or inside one,
# no switch on the coupling method or the solver engine outside their tables, src/app/ the
# command line only. It fails on the tree before issue 15 (solvers -> pd -> solvers).
set -euo pipefail
exec /usr/bin/python3 "${CUPID_SOURCE_DIR:?}/scripts/check_architecture.py" -v "$CUPID_SOURCE_DIR"
