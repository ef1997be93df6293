// A sphere of radius 4 centred at (5, 5, 5) as a CAD solid (OpenCASCADE), for
// tests/verification/pd_geometry.sh: its lattice nodes against the analytic sphere's.
SetFactory("OpenCASCADE");
Sphere(1) = {5, 5, 5, 4};
