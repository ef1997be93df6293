// A thin tube's section (outer radius 10, wall 2) for a CUF beam with a meshed section
// (beam.section.mesh; examples/sections/README.md): four quarter rings of structured
// quadrilaterals, 8 along each quarter and 2 through the wall; Gmsh's x, y are the section's
// x, z. With element: L9 the quadrilaterals become 9-node elements whose edges follow the arcs.
Ri = 8;
Ro = 10;
nc = 8;  // elements along each quarter
nr = 2;  // elements through the wall

Point(1) = {0, 0, 0};
Point(2) = {Ri, 0, 0}; Point(3) = {0, Ri, 0}; Point(4) = {-Ri, 0, 0}; Point(5) = {0, -Ri, 0};
Point(6) = {Ro, 0, 0}; Point(7) = {0, Ro, 0}; Point(8) = {-Ro, 0, 0}; Point(9) = {0, -Ro, 0};
Circle(1) = {2, 1, 3}; Circle(2) = {3, 1, 4}; Circle(3) = {4, 1, 5}; Circle(4) = {5, 1, 2};
Circle(5) = {6, 1, 7}; Circle(6) = {7, 1, 8}; Circle(7) = {8, 1, 9}; Circle(8) = {9, 1, 6};
Line(9) = {2, 6}; Line(10) = {3, 7}; Line(11) = {4, 8}; Line(12) = {5, 9};
Curve Loop(1) = {9, 5, -10, -1}; Plane Surface(1) = {1};
Curve Loop(2) = {10, 6, -11, -2}; Plane Surface(2) = {2};
Curve Loop(3) = {11, 7, -12, -3}; Plane Surface(3) = {3};
Curve Loop(4) = {12, 8, -9, -4}; Plane Surface(4) = {4};
Transfinite Curve{1:8} = nc + 1;
Transfinite Curve{9:12} = nr + 1;
Transfinite Surface{1:4};
Recombine Surface{1:4};
Physical Surface("tube") = {1:4};
