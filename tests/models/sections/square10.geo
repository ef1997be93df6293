// The 10 x 10 section of examples/bar/bar_coupled_arlequin_l9.yaml as one Gmsh quadrilateral
// (tests/verification/section_mesh.sh: a full-section coupling on a meshed section).
Point(1) = {0, 0, 0}; Point(2) = {10, 0, 0}; Point(3) = {10, 10, 0}; Point(4) = {0, 10, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{:} = 2;
Transfinite Surface{1};
Recombine Surface{1};
