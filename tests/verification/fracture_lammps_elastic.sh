#!/usr/bin/env bash
# The elastic pre-check of the LAMMPS dynamic-fracture comparison (fracture_lammps/README.md):
# cupid's bond-based PMB plate (micromodulus 18 K / S, PDLAMMPS partial volumes, central
# differences) released with a linear velocity field must follow the stored LAMMPS peri/pmb run
# (fracture_lammps/elastic_lammps.csv) to 1e-3 of the amplitude at every step (measured 1.5e-4:
# LAMMPS's stretch is nonlinear; the difference scales with the strain). LAMMPS is not needed.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
D=$SRC/tests/verification/fracture_lammps

"$CUPID" run "$D/elastic_check.yaml" -o elastic --quiet && ok || bad "cupid run elastic_check.yaml"
python3 "$D/compare_elastic.py" elastic/history.csv && ok || bad "cupid vs LAMMPS displacement histories"

finish fracture_lammps_elastic
