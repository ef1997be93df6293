// A cylinder along z, radius 8 about (30, 30), from z = -1 to 4 (through a 3 mm plate), as a
// CAD solid: examples/geometry/plate_hole.yaml's hole as a geometry file
// (tests/verification/pd_geometry.sh).
SetFactory("OpenCASCADE");
Cylinder(1) = {30, 30, -1, 0, 0, 5, 8};
