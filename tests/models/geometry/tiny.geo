// A sphere of radius 0.1 between the cell centres of a lattice of spacing 1: no node inside.
SetFactory("OpenCASCADE");
Sphere(1) = {1, 1, 1, 0.1};
