#!/usr/bin/env bash
# The C-beam with PD around its web-flange corner (cbeam_corner.yaml), coupled by paper 000's
# fictitious nodes as published (balance: none) and balanced (balance: momentum), against the
# full L9 beam: the error of u_z along the flange tip (x = 45, z = 47.5) as a plot,
# out/cbeam/balance/balance_error.png (the picture in examples/cbeam/README.md).
# usage: examples/cbeam/balance.sh [path/to/cupid]   (~20 s on 2 cores; needs gnuplot)
set -euo pipefail
cd "$(dirname "$0")/../.."
CUPID=${1:-build/cupid}
out=out/cbeam/balance
mkdir -p "$out"
"$CUPID" run examples/cbeam/cbeam_fe_l9.yaml -o "$out/fe" --quiet
for b in none momentum; do
  "$CUPID" run examples/cbeam/cbeam_corner.yaml -o "$out/$b" --solver krylov --quiet \
    --set coupling.balance=$b
done
# y, error of u_z (%) for each form, from the two lines sampled at the same points
paste -d, "$out/fe/line_flange_tip.csv" "$out/none/line_flange_tip.csv" "$out/momentum/line_flange_tip.csv" |
  awk -F, 'NR > 1 && $7 != 0 { printf "%s %.6f %.6f\n", $3, 100 * ($15 / $7 - 1), 100 * ($23 / $7 - 1) }' \
  > "$out/error.dat"
gnuplot <<GP
set terminal pngcairo size 900,500 font ",11"
set output "$out/balance_error.png"
set title "C-beam, PD around the web-flange corner (y 490-510): u_z along the flange tip against full L9"
set xlabel "y [mm]"
set ylabel "error of u_z [%]"
set grid
set key center right
set xrange [20:1000]
set arrow from 490, graph 0 to 490, graph 1 nohead dt 2 lc rgb "gray"
set arrow from 510, graph 0 to 510, graph 1 nohead dt 2 lc rgb "gray"
plot "$out/error.dat" u 1:2 w lp pt 7 ps 0.4 lw 2 t "paper 000 (balance: none)", \
     "$out/error.dat" u 1:3 w lp pt 5 ps 0.4 lw 2 t "balanced (balance: momentum)"
GP
echo "wrote $out/balance_error.png"
awk 'END { printf "free end: none %+.3f%%, momentum %+.3f%%\n", $2, $3 }' "$out/error.dat"
