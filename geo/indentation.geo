// Indentation of an elastic cylindrical punch into an elasto-plastic foundation (paper §4.3,
// Fig. 7), axisymmetric (x = r, y = z). Punch: 0 <= r <= a, H <= z <= H + h. Foundation:
// 0 <= r <= A, 0 <= z <= H. The paper's dimensions are the defaults: 2a = 20, h = 20,
// 2A = 80, H = 40 (mm).
//
// The two bodies have coincident but distinct nodes on the contact 0 <= r <= a, z = H
// (Geometry.AutoCoherence = 0; the punch bottom and the foundation top under the punch are
// two curves with the same transfinite distribution). Quadratic quads (the run sets
// Mesh.SecondOrderIncomplete = 1), graded geometrically toward the punch corner (r = a,
// z = H), where the contact stresses are singular and the foundation first yields: every
// curve that ends at the corner starts there with the same element size and grows by the
// same ratio q per element, so the elements at the corner are about square.
//
// Physical groups: surfaces "punch", "foundation"; curves "punch_face" (punch bottom, the
// contact side of the punch), "foundation_contact" (foundation top under the punch),
// "punch_top" (loaded), "punch_side" (r = a, free), "foundation_free_top" (a <= r <= A,
// z = H, free), "foundation_outer" (r = A, free), "foundation_bottom" (supported, u_z = 0),
// "symmetry_axis" (r = 0 of both bodies; asperity sets u_r = 0 there by itself).
// Run: gmsh indentation.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1
//      [-setnumber a 10 -setnumber h 20 -setnumber A 40 -setnumber H 40 -setnumber n 20
//       -setnumber grading 6 -clscale 1]
DefineConstant[ a = {10, Name "punch radius a [mm]"} ];
DefineConstant[ h = {20, Name "punch height h [mm]"} ];
DefineConstant[ A = {40, Name "foundation radius A [mm]"} ];
DefineConstant[ H = {40, Name "foundation height H [mm]"} ];
DefineConstant[ n = {20, Name "elements along the contact 0 <= r <= a (at size factor 1)"} ];
DefineConstant[ grading = {6, Name "size ratio of the first to the last contact element (axis / corner)"} ];

// Elements scale with the size factor: -clscale s gives about n / s along the contact.
s = Mesh.MeshSizeFactor;
nc = Ceil(n / s);
Mesh.MeshSizeFactor = 1;
// Growth ratio q per element away from the corner, and the corner element size d0.
q = grading^(1 / (nc - 1));
d0 = a * (q - 1) / (q^nc - 1);
// Number of elements of a curve of length L starting with d0 and growing by q (at least 2).
nf = Ceil(Log(1 + (H) * (q - 1) / d0) / Log(q));   // foundation height, graded to the top
no = Ceil(Log(1 + (A - a) * (q - 1) / d0) / Log(q)); // foundation radius beyond the punch
np = Ceil(Log(1 + (h) * (q - 1) / d0) / Log(q));   // punch height, graded to the bottom
nf = (nf < 2) ? 2 : nf;
no = (no < 2) ? 2 : no;
np = (np < 2) ? 2 : np;

Geometry.AutoCoherence = 0;

// Foundation: inner block 0 <= r <= a (surface 1) and outer block a <= r <= A (surface 2).
Point(1) = {0, 0, 0};  Point(2) = {a, 0, 0};  Point(3) = {A, 0, 0};
Point(4) = {0, H, 0};  Point(5) = {a, H, 0};  Point(6) = {A, H, 0};
Line(1) = {1, 2};   // bottom, inner
Line(2) = {2, 3};   // bottom, outer
Line(3) = {1, 4};   // axis
Line(4) = {2, 5};   // r = a inside the foundation, upward to the corner
Line(5) = {3, 6};   // outer surface r = A
Line(6) = {4, 5};   // contact under the punch, axis -> corner
Line(7) = {5, 6};   // free top, corner -> outside
Curve Loop(1) = {1, 4, -6, -3}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 5, -7, -4}; Plane Surface(2) = {2};

// Punch (surface 3): its own corner points at z = H (distinct nodes).
Point(7) = {0, H, 0};  Point(8) = {a, H, 0};
Point(9) = {0, H + h, 0};  Point(10) = {a, H + h, 0};
Line(8) = {7, 8};    // punch face, axis -> corner (same distribution as line 6)
Line(9) = {8, 10};   // punch side, corner -> top
Line(10) = {9, 10};  // punch top
Line(11) = {7, 9};   // axis
Curve Loop(3) = {8, 9, -10, -11}; Plane Surface(3) = {3};

// Progression r < 1 shrinks the elements along the curve's direction. Curves toward the
// corner (6, 8, 4 and the opposite 1, 3, 10) shrink by 1/q; curves away from it (7, 9 and the
// opposite 2, 5, 11) grow by q. The far sides follow the near ones so the grid lines stay
// straight.
Transfinite Curve{6, 8, 1, 10} = nc + 1 Using Progression 1 / q;
Transfinite Curve{4, 3} = nf + 1 Using Progression 1 / q;
Transfinite Curve{5} = nf + 1 Using Progression 1 / q;
Transfinite Curve{7, 2} = no + 1 Using Progression q;
Transfinite Curve{9, 11} = np + 1 Using Progression q;
Transfinite Surface{1, 2, 3};
Recombine Surface{1, 2, 3};

Physical Surface("foundation") = {1, 2};
Physical Surface("punch") = {3};
Physical Curve("punch_face") = {8};
Physical Curve("foundation_contact") = {6};
Physical Curve("punch_top") = {10};
Physical Curve("punch_side") = {9};
Physical Curve("foundation_free_top") = {7};
Physical Curve("foundation_outer") = {5};
Physical Curve("foundation_bottom") = {1, 2};
Physical Curve("symmetry_axis") = {3, 11};
