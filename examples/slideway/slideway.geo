// A machine-tool slideway: a carriage (a long block) on a bed, plane strain, joined by a
// rough joint along the carriage's underside and pushed along the bed at its rear face by
// the feed drive. The bed is longer than the carriage; the joint is the carriage's whole
// length. Coincident but distinct nodes along the joint
// (Geometry.AutoCoherence = 0), the same number of elements on both sides.
// Physical groups: surfaces "bed", "carriage"; curves "bed_base" (held), "bed_top"
// (the bed's side of the joint), "carriage_bottom" (the carriage's side), "carriage_top"
// (clamped), "carriage_rear" (driven, x = x0).
DefineConstant[ L = {200, Name "carriage length L [mm]"} ];
DefineConstant[ h = {25, Name "carriage height h [mm]"} ];
DefineConstant[ B = {260, Name "bed length B [mm]"} ];
DefineConstant[ H = {40, Name "bed height H [mm]"} ];
DefineConstant[ n = {50, Name "elements along the joint"} ];
Geometry.AutoCoherence = 0;
x0 = (B - L) / 2; x1 = x0 + L;
f = Mesh.MeshSizeFactor;
// bed: the joint segment is a curve of its own
Point(1) = {0, 0, 0}; Point(2) = {B, 0, 0}; Point(3) = {B, H, 0};
Point(4) = {x1, H, 0}; Point(5) = {x0, H, 0}; Point(6) = {0, H, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
// carriage: its own points along the joint
Point(7) = {x0, H, 0}; Point(8) = {x1, H, 0}; Point(9) = {x1, H + h, 0}; Point(10) = {x0, H + h, 0};
Line(7) = {7, 8}; Line(8) = {8, 9}; Line(9) = {9, 10}; Line(10) = {10, 7};
Curve Loop(2) = {7, 8, 9, 10}; Plane Surface(2) = {2};
// the same nodes on both sides of the joint; the size factor scales the counts
m = Ceil(n / f);
Transfinite Curve{4, 7, 9} = m + 1;
Transfinite Curve{8, 10} = Ceil(m * h / L) + 1;
Transfinite Surface{2};
MeshSize{1, 2, 3, 6} = L / m * 3;
Recombine Surface{1, 2};
Physical Surface("bed") = {1};
Physical Surface("carriage") = {2};
Physical Curve("bed_base") = {1};
Physical Curve("bed_top") = {4};
Physical Curve("carriage_bottom") = {7};
Physical Curve("carriage_top") = {9};
Physical Curve("carriage_rear") = {10};
