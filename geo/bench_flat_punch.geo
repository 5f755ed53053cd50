// Benchmark against CalculiX (benches/calculix): cylindrical flat punch of radius a and
// height h pressed onto a foundation 20a wide and 20a deep, axisymmetric (x = r, y = z); the
// geometry and grading of geo/flat_punch.geo, kept separate so that the benchmark does not
// change when the example does.
// Two bodies with coincident but distinct nodes on the contact (Geometry.AutoCoherence = 0).
// Physical groups: surfaces "foundation", "punch"; curves "surface" (foundation under the
// punch, contact side A), "face" (punch bottom, side B), "top" (punch top, load), "base"
// (foundation bottom, support), "foundation_top", "outer"; points "centre" (foundation surface
// on the axis) and "top_centre" (punch top on the axis), where the benchmark compares the
// axial displacement.
// Size: about 2 800 / s^2 unknowns with the defaults (s = -clscale).
DefineConstant[ a = {10, Name "punch radius a [mm]"} ];
DefineConstant[ h = {10, Name "punch height [mm]"} ];
DefineConstant[ n_punch = {16, Name "elements under the punch (size factor 1)"} ];
DefineConstant[ n_out = {12, Name "elements from the punch edge to r = 20a (size factor 1)"} ];
DefineConstant[ n_depth = {14, Name "elements through the depth (size factor 1)"} ];
DefineConstant[ n_height = {4, Name "elements through the punch height (size factor 1)"} ];

s = Mesh.MeshSizeFactor;
np = Ceil(n_punch / s);
no = Ceil(n_out / s);
nd = Ceil(n_depth / s);
nh = Ceil(n_height / s);
Mesh.MeshSizeFactor = 1;
Geometry.AutoCoherence = 0;

W = 20 * a;
D = 20 * a;

Point(1) = {0, 0, 0}; Point(2) = {a, 0, 0}; Point(3) = {W, 0, 0};
Point(4) = {W, D, 0}; Point(5) = {a, D, 0}; Point(6) = {0, D, 0};
Line(1) = {1, 2};  // base under the punch
Line(2) = {2, 3};  // base outside (outwards)
Line(3) = {3, 4};  // outer (upwards)
Line(4) = {5, 4};  // free surface (outwards)
Line(5) = {5, 6};  // surface under the punch
Line(6) = {1, 6};  // axis (upwards)
Line(7) = {2, 5};  // below the punch edge (upwards)
Curve Loop(1) = {1, 7, 5, -6}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, -4, -7}; Plane Surface(2) = {2};

Point(11) = {0, D, 0}; Point(12) = {a, D, 0}; Point(13) = {a, D + h, 0}; Point(14) = {0, D + h, 0};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(3) = {11, 12, 13, 14}; Plane Surface(3) = {3};

Transfinite Curve{1, 5, 11, 13} = np + 1;
Transfinite Curve{2, 4} = no + 1 Using Progression 1.35^(12 / no);
Transfinite Curve{3, 6, 7} = nd + 1 Using Progression 0.72^(14 / nd);
Transfinite Curve{12, 14} = nh + 1;
Transfinite Surface{1, 2, 3};
Recombine Surface{1, 2, 3};

Physical Surface("foundation") = {1, 2};
Physical Surface("punch") = {3};
Physical Curve("surface") = {5};
Physical Curve("face") = {11};
Physical Curve("top") = {13};
Physical Curve("base") = {1, 2};
Physical Curve("foundation_top") = {4};
Physical Curve("outer") = {3};
Physical Point("centre") = {6};
Physical Point("top_centre") = {14};
