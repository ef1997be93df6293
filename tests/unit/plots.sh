#!/usr/bin/env bash
# What a person sees in the plots (issue 19 item 8): axes labelled with the model's quantities
# (the coordinate a line runs along, the displacement components shown), curves that are zero
# everywhere left out (named in the script), the energy total drawn visibly, scripts that
# gnuplot runs from any folder; a dynamic summary reports its energy balance, not a static
# equilibrium imbalance.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
command -v gnuplot >/dev/null || { echo "FAIL: gnuplot (gnuplot-nox, scripts/install-deps.sh) is not installed"; exit 1; }
"$CUPID" run "$SRC/examples/pd_bar/pd_bar.yaml" -o bar --quiet || bad "pd_bar run"
gp=bar/line_axis.gp
grep -q "set xlabel 'y'" $gp && ok || bad "line x label: $(grep xlabel $gp)"
grep -q "set ylabel 'u_y'" $gp && ok || bad "line y label: $(grep ylabel $gp)"
grep -q "# left out, zero everywhere: u_x" $gp && grep -q "# left out, zero everywhere: u_z" $gp && ok || bad "zero curves kept"
[ "$(grep -c "using" $gp)" -eq 1 ] && ok || bad "more than the u_y curve plotted"
rm -f bar/line_axis.png
mkdir -p elsewhere && (cd elsewhere && gnuplot ../$gp) && [ -s bar/line_axis.png ] && ok || bad "the script does not run from another folder"
sed 's/  plots: false/  plots: true/' "$SRC/tests/models/dynamics/fe_truss.yaml" > truss.yaml
"$CUPID" run truss.yaml -o truss --quiet || bad "truss run"
grep -q "set ylabel 'u_y'" truss/history_tip.gp && ok || bad "history y label: $(grep ylabel truss/history_tip.gp)"
grep -q "title 'total'" truss/energies.gp && grep "title 'total'" truss/energies.gp | grep -q "lw 3" && ok || bad "the total energy is not drawn thick"
/usr/bin/python3 -c "
import json, sys
s = json.load(open('truss/summary.json'))
sys.exit(0 if 'energy_balance' in s and 'equilibrium_imbalance' not in s else 1)" && ok || bad "dynamic summary: energy balance"
finish plots
