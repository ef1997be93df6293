// The plate with a hole of examples/geometry/plate_hole.yaml as a CAD solid (OpenCASCADE):
// 60 x 60 x 3 mm, a hole of radius 8 mm through its middle.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 60, 3};
Cylinder(2) = {30, 30, -1, 0, 0, 5, 8};
BooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};
