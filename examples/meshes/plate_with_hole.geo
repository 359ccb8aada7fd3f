// A 4 x 2 plate with a circular hole of radius 0.5 at (1, 1), meshed with
// quadrilaterals (recombined), physical groups naming the body and its sides.
// Regenerate: gmsh -2 -format msh41 plate_with_hole.geo -o plate_with_hole.msh
lc = 0.25;
Point(1) = {0, 0, 0, lc};
Point(2) = {4, 0, 0, lc};
Point(3) = {4, 2, 0, lc};
Point(4) = {0, 2, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {1.5, 1, 0, lc};
Point(7) = {1, 1.5, 0, lc};
Point(8) = {0.5, 1, 0, lc};
Point(9) = {1, 0.5, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Circle(5) = {6, 5, 7};
Circle(6) = {7, 5, 8};
Circle(7) = {8, 5, 9};
Circle(8) = {9, 5, 6};
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};
Recombine Surface{1};
Mesh.Algorithm = 6;
Mesh.RecombinationAlgorithm = 1;
Physical Surface("plate") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("hole") = {5, 6, 7, 8};
