// Prandtl's flat punch on a perfectly plastic half-space, plane strain (x, y), y = 0 the
// surface, the half-space y < 0. By symmetry only x >= 0 is modelled: a smooth rigid punch
// of half-width a covers 0 <= x <= a. The half-space is cut off at x = W a and y = -D a, far
// enough outside Prandtl's mechanism (it reaches x = 3a and a depth of about 1.6a) that the
// cut-off does not change the collapse load (q = (2 + pi) k, k = sigma_Y / sqrt 3).
//
// With punch = 1 (default) the punch is a body of its own, a block a wide and a/2 high on
// the face, meshed conformingly with the half-space: a case splits the face into a
// frictionless contact pair ([[contact]] curve = "face") and drives the punch through its
// top. With punch = 0 there is only the half-space and the face is driven directly.
//
// Mesh: unstructured quads (triangles with recombine = 0), size h = a / n_punch in the
// mechanism zone [0, 3.5a] x [-2a, 0], graded down to h / edge_refinement at the punch edge
// (the stress singularity) and growing to far * h away from it. Element sizes scale with the
// size factor (-clscale).
//
// Physical groups: surfaces "half_space", "punch"; curves "face" (0 <= x <= a on y = 0:
// under the punch), "surface" (a <= x <= W a on y = 0: free), "symmetry" (x = 0, half-space),
// "base" (y = -D a), "far" (x = W a), "punch_axis" (x = 0, punch), "top" (punch top); point
// "edge" (the punch edge).
// Run: gmsh prandtl.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1
//      [-setnumber a 10 -setnumber n_punch 8 -setnumber edge_refinement 4 -clscale s]
DefineConstant[ a = {10, Name "punch half-width a [mm]"} ];
DefineConstant[ W = {6, Name "model width / a"} ];
DefineConstant[ D = {5, Name "model depth / a"} ];
DefineConstant[ n_punch = {8, Name "elements across the punch half-width (size factor 1)"} ];
DefineConstant[ edge_refinement = {4, Name "size ratio mechanism zone / punch edge"} ];
DefineConstant[ far = {4, Name "size ratio far field / mechanism zone"} ];
DefineConstant[ recombine = {1, Name "1: quads (quad8), 0: triangles (tri6)"} ];
DefineConstant[ punch = {1, Name "1: punch body on the face, 0: half-space only"} ];

h = a / n_punch;
Point(1) = {0, 0, 0};
Point(2) = {a, 0, 0};
Point(3) = {W * a, 0, 0};
Point(4) = {W * a, -D * a, 0};
Point(5) = {0, -D * a, 0};
Line(1) = {1, 2};  // punch face
Line(2) = {2, 3};  // free surface
Line(3) = {3, 4};  // far side
Line(4) = {4, 5};  // base
Line(5) = {5, 1};  // symmetry axis
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
If (punch)
  Point(6) = {a, a / 2, 0};
  Point(7) = {0, a / 2, 0};
  Line(6) = {2, 6};  // punch side
  Line(7) = {6, 7};  // punch top
  Line(8) = {7, 1};  // punch axis
  Curve Loop(2) = {1, 6, 7, 8};
  Plane Surface(2) = {2};
EndIf

// Sizes: the smaller of a box over the mechanism zone and a ball around the punch edge.
Field[1] = Box;
Field[1].VIn = h;
Field[1].VOut = far * h;
Field[1].XMin = 0; Field[1].XMax = 3.5 * a;
Field[1].YMin = -2 * a; Field[1].YMax = 0;
Field[1].Thickness = 1.5 * a;
Field[2] = Distance;
Field[2].PointsList = {2};
Field[3] = Threshold;
Field[3].InField = 2;
Field[3].SizeMin = h / edge_refinement;
Field[3].SizeMax = far * h;
Field[3].DistMin = 0.05 * a;
Field[3].DistMax = 1.0 * a;
Field[4] = Min;
Field[4].FieldsList = {1, 3};
Background Field = 4;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

If (recombine)
  Mesh.Algorithm = 6;              // frontal-Delaunay (8, its quad variant, crashes gmsh 4.8)
  Mesh.RecombinationAlgorithm = 1; // blossom
  Recombine Surface{:};
EndIf

Physical Surface("half_space") = {1};
Physical Curve("face") = {1};
Physical Curve("surface") = {2};
Physical Curve("far") = {3};
Physical Curve("base") = {4};
Physical Curve("symmetry") = {5};
Physical Point("edge") = {2};
If (punch)
  Physical Surface("punch") = {2};
  Physical Curve("top") = {7};
  Physical Curve("punch_axis") = {8};
EndIf
