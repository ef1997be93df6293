#!/usr/bin/env bash
# Coupled models that cupid cannot run give a clear model error naming the file position and
# what to change: a PD region bound that is not a beam-element end, a region over part of the
# section that cuts section elements or removes part of a TE expansion, Arlequin layouts it does not
# cannot take (an overlap that starts on no region face; two overlaps on one face; an
# interface face without an overlap; an overlap on a free surface; an overlap bound that cuts a
# section element; a slab along two axes, or bounded on two with `along` naming neither).
# Each case must fail (non-zero exit) with the expected phrase in the message.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0; pass=0
model() { # $1 region, $2 coupling
cat <<EOF2
materials:
  m: {E: 1000, nu: 0.2}
beam:
  material: m
  axis: {y: [0, 10, 20, 30], elements: [1, 1, 1], type: B2}
  section:
    expansion: LE
    element: L4
    components:
      - {x: [0, 4, 8], z: [0, 8]}
peridynamics:
  spacing: 1.0
  horizon: 1.5
  material: m
  regions:
    - $1
coupling: $2
constraints:
  - clamp: {y: 0}
loads:
  - traction: {y: 30, value: [0, 1, 0]}
EOF2
}
check() { # $1 name, $2 expected phrase; model on stdin
  cat > "$work/$1.yaml"
  out=$("$CUPID" check "$work/$1.yaml" 2>&1); rc=$?
  if [ $rc -ne 0 ] && grep -q -- "$2" <<<"$out"; then
    pass=$((pass+1)); echo "ok: $1: $(grep -m1 -- "$2" <<<"$out")"
  else
    fail=$((fail+1)); echo "FAIL: $1 (rc $rc): $out"
  fi
}
check unaligned "bound y = 15 is not a beam-element end" < <(model "{x: [0, 8], y: [10, 15], z: [0, 8]}" "{method: fictitious}")
check partial_edge "bound x = 3 is not a section-element edge" < <(model "{x: [0, 3], y: [10, 20], z: [0, 8]}" "{method: fictitious}")
check partial_te "TE expansion spans the whole section" < <(model "{x: [0, 4], y: [10, 20], z: [0, 8]}" "{method: fictitious}" | sed 's/expansion: LE/expansion: TE2/; /element: L4/d')
fine() { sed 's/y: \[0, 10, 20, 30\], elements: \[1, 1, 1\]/y: [0, 10, 15, 20, 30], elements: [1, 1, 1, 1]/'; }
arl() { echo "{method: arlequin, arlequin: {penalty: 1000, overlap: $1}}"; }
check arlequin "starts on no face of a PD region" < <(model "{x: [0, 8], y: [10, 20], z: [0, 8]}" "$(arl "{y: [8, 12]}")")
check arlequin_two "two overlaps on the face y = 10" < <(model "{x: [0, 8], y: [10, 20], z: [0, 8]}" "$(arl "[{y: [10, 20]}, {y: [10, 20]}]")")
check arlequin_face "the face y = 20 of this PD region meets the beam: give it an overlap" < <(model "{x: [0, 8], y: [10, 20], z: [0, 8]}" "$(arl "{y: [10, 15]}")" | fine)
half="{x: [0, 4], y: [10, 20], z: [0, 8]}"
check arlequin_parallel "the face x = 4 of this PD region meets the beam" < <(model "$half" "$(arl "[{y: [10, 15]}, {y: [15, 20]}]")" | fine)
# (a slab spanning the region along x would serve its face x = 4, the one the beam meets)
halves() { fine | sed 's/x: \[0, 4, 8\]/x: [0, 2, 4, 8]/'; }
check arlequin_free "where the beam does not continue (a free surface)" < <(model "$half" "$(arl "[{y: [10, 15]}, {y: [15, 20]}, {x: [0, 2]}]")" | halves)
check arlequin_cut "the overlap bound x = 2 cuts a section element" < <(model "$half" "$(arl "[{y: [10, 15]}, {y: [15, 20]}, {x: [2, 4]}]")" | fine)
check arlequin_axes "give exactly one of x, y, z" < <(model "{x: [0, 8], y: [10, 20], z: [0, 8]}" "$(arl "{x: [0, 8], y: [10, 12]}")")
check arlequin_along "the overlap ramps along z, and gives no z range" < <(model "{x: [0, 8], y: [10, 20], z: [0, 8]}" "$(arl "{x: [0, 8], y: [10, 12], along: z}")")

echo "coupling_errors: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
