// Plane elastic punch on an elastic foundation: example 4.1 of Buczkowski & Kleiber (1994),
// Figs. 2-4 (the paper's §4.1).
//
// The paper does not give the geometry of this example (it is in Fredriksson 1976, not in the
// text; see docs/theory.md, "The paper's examples: data and choices"). Chosen here, all of
// them parameters below:
//   punch (body B, on top)    width 2a = 100 mm (a = 50), height h = 50 mm;
//   foundation (body A)       width 2W = 600 mm (W = 6a: 5a beyond each punch edge),
//                             depth D = 250 mm (5a), bottom held vertically.
// Only the half x >= 0 is modelled (symmetry line x = 0: u_x = 0 there, group "symmetry").
// Plane stress (thickness set in the case), because the paper's study is "a plane stress and
// axisymmetric ... contact problem" (§1) and the punch, loaded on its own top face only, is
// free to expand in z.
//
// The two bodies have coincident but distinct nodes along the contact 0 <= x <= a, y = 0
// (Geometry.AutoCoherence = 0): the punch bottom "punch_face" and the foundation's top under
// the punch "foundation_contact" are transfinite curves with the same node count and the
// same geometric progression toward the punch corner (x = a), where the slip is largest.
// Elsewhere the mesh is unstructured, recombined into quads, with an element size growing
// linearly with the distance d from the corner at the rate of the contact progression:
// size(d) = min(h_far, h_corner + (1/r - 1) d). Quadratic serendipity quads come from
// asperity's meshing command (-order 2, Mesh.SecondOrderIncomplete = 1).
//
// Mesh density: n_contact elements along the half-face at size factor 1, the corner element
// `grading` times the one at the centre. -clscale s (case `size`) divides n_contact by s
// and multiplies h_far by s (as in thick_cylinder_axi.geo), keeping the grading.
//
// Physical groups: surfaces "punch", "foundation"; curves "punch_face", "foundation_contact"
// (contact sides), "punch_top" (loaded), "punch_side", "foundation_free" (top beyond the
// punch), "foundation_side" (x = W), "foundation_bottom" (y = -D), "symmetry" (x = 0 of
// both bodies).
// Run: gmsh plane_punch.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1 -format msh41
//      [-setnumber a 50 -setnumber h 50 -setnumber W 300 -setnumber D 250
//       -setnumber n_contact 32 -setnumber grading 0.05 -setnumber h_far 25 -clscale 1]
DefineConstant[ a = {50, Name "punch half-width a [mm]"} ];
DefineConstant[ h = {50, Name "punch height h [mm]"} ];
DefineConstant[ W = {300, Name "foundation half-width W [mm]"} ];
DefineConstant[ D = {250, Name "foundation depth D [mm]"} ];
DefineConstant[ n_contact = {32, Name "elements along the half contact face (size factor 1)"} ];
DefineConstant[ grading = {0.05, Name "corner element / centre element along the contact"} ];
DefineConstant[ h_far = {25, Name "largest element size [mm] (size factor 1)"} ];

s = Mesh.MeshSizeFactor;
nc = Ceil(n_contact / s);
hmax = h_far * s;
Mesh.MeshSizeFactor = 1;
// Geometric progression along the face, elements shrinking toward x = a by the ratio r.
r = grading^(1 / (nc - 1));
h_centre = a * (1 - r) / (1 - r^nc);
h_corner = h_centre * r^(nc - 1);
growth = 1 / r - 1;

Geometry.AutoCoherence = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.Algorithm = 6;              // frontal-Delaunay (8, "for quads", segfaults in gmsh 4.8.4)
Mesh.RecombinationAlgorithm = 1; // blossom

// Foundation (body A): 0 <= x <= W, -D <= y <= 0.
Point(1) = {0, -D, 0};
Point(2) = {W, -D, 0};
Point(3) = {W, 0, 0};
Point(4) = {a, 0, 0};
Point(5) = {0, 0, 0};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // far side x = W
Line(3) = {3, 4};   // free top beyond the punch
Line(4) = {5, 4};   // contact, x from 0 to a
Line(5) = {5, 1};   // symmetry
Curve Loop(1) = {1, 2, 3, -4, 5};
Plane Surface(1) = {1};

// Punch (body B): 0 <= x <= a, 0 <= y <= h; its own points on y = 0.
Point(11) = {0, 0, 0};
Point(12) = {a, 0, 0};
Point(13) = {a, h, 0};
Point(14) = {0, h, 0};
Line(11) = {11, 12}; // contact face, x from 0 to a
Line(12) = {12, 13}; // side
Line(13) = {13, 14}; // top (loaded)
Line(14) = {14, 11}; // symmetry
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};

// Identical node distributions on both contact sides, graded toward the corner x = a.
Transfinite Curve{4, 11} = nc + 1 Using Progression r;

Field[1] = Distance;
Field[1].PointsList = {4, 12};
Field[2] = MathEval;
Field[2].F = Sprintf("min(%g, %g + %g * F1)", hmax, h_corner, growth);
Background Field = 2;
Recombine Surface{1, 2};

Physical Surface("foundation") = {1};
Physical Surface("punch") = {2};
Physical Curve("foundation_contact") = {4};
Physical Curve("punch_face") = {11};
Physical Curve("punch_top") = {13};
Physical Curve("punch_side") = {12};
Physical Curve("foundation_free") = {3};
Physical Curve("foundation_side") = {2};
Physical Curve("foundation_bottom") = {1};
Physical Curve("symmetry") = {5, 14};
