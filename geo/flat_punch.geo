// Frictionless flat punch on an elastic foundation, axisymmetric (x = r, y = z): a stiff
// cylindrical punch of radius a pressed onto a foundation 20a wide and 20a deep, as in
// tests/contact.rs (mod flat_punch). Validation against Sneddon's rigid flat punch on a half
// space (Sneddon 1946; docs/theory.md, "Rigid flat punch on a half-space"):
// p(r) = p_m / (2 sqrt(1 - r²/a²)), p_m = P / (π a²), singular at the punch edge r = a.
//
// Two bodies with coincident but distinct nodes on the contact (Geometry.AutoCoherence = 0).
// The foundation is graded: uniform under the punch (n_punch elements), growing
// geometrically outwards (n_out elements, ratio 1.35 at size factor 1) and shrinking towards
// the surface (n_depth elements, ratio 0.72). Element counts scale with the size factor
// (-clscale s: about n / s elements) and the grading ratios with them (ratio^(n/n_s)), so
// halving s splits every element in about two in each direction: a nested-like family for
// refinement studies.
//
// Physical groups: surfaces "foundation", "punch"; curves "surface" (foundation under the
// punch, side A of the contact), "face" (punch bottom, side B), "top" (punch top, load),
// "base" (foundation bottom, support), "foundation_top" (free surface outside the punch),
// "outer" (r = 20a); point "centre" (the foundation surface on the axis).
// Run: gmsh flat_punch.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1
//      [-setnumber a 10 -setnumber n_punch 16 -clscale s]
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

// Foundation: a column under the punch and the graded region outside it.
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

// Punch: its own points on the contact.
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
