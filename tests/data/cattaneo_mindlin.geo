// Cattaneo–Mindlin partial slip, plane strain (tests/cattaneo_mindlin.rs, docs/fretting.md):
// the lower half of a cylinder of radius R (centre (0, R), touching the flat at the origin)
// on a flat block [-L, L] x [-D, 0]. The contact faces span x = -w..w (w somewhat larger
// than the Hertz half-width a) and are made of n one-element pieces whose end points have
// the same abscissae on both faces, x_i = -w + 2 w i / n, so that the "ordered" pairing joins
// nodes that lie on one vertical: the initial gap of a pair is then exactly the Hertz gap
// x_i^2 / (2R) + O(x^4 / R^3) and carries no tangential offset.
// Groups: bodies "cylinder", "block"; contact faces "flat" (block) and "arc" (cylinder);
// "bottom" (block, held), "top" = "top_left" + "top_right" (the cylinder's diametral plane,
// loaded; the halves carry the couple that cancels the moment of the shear load about the
// contact, see docs/fretting.md).
// Mesh: triangles, element size hc = 2w/n along the contact and inside a disc of radius w
// about it, growing linearly to lc far away; refine with n and the size factor together.
DefineConstant[ R = 200, L = 200, D = 200, w = 1.2, n = 48, lc = 25, growth = 0.25 ];
Geometry.AutoCoherence = 0;   // the two faces touch at the origin with distinct nodes
hc = 2 * w / n;

// Contact faces: points 1000+i on the flat, 2000+i on the arc; centre of the cylinder 3.
Point(3) = {0, R, 0, lc};
For i In {0:n}
  x = -w + 2 * w * i / n;
  Point(1000 + i) = {x, 0, 0, hc};
  Point(2000 + i) = {x, R - Sqrt(R * R - x * x), 0, hc};
EndFor
For i In {0:n-1}
  Line(1000 + i) = {1000 + i, 1001 + i};
  Circle(2000 + i) = {2000 + i, 3, 2001 + i};
  Transfinite Curve{1000 + i, 2000 + i} = 2;
EndFor

// Block: bottom-left, bottom-right, top-right, top-left corners.
Point(11) = {-L, -D, 0, lc}; Point(12) = {L, -D, 0, lc};
Point(13) = {L, 0, 0, lc}; Point(14) = {-L, 0, 0, lc};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 1000 + n};
Line(14) = {1000, 14}; Line(15) = {14, 11};
Curve Loop(1) = {11, 12, 13, -(1000 + n - 1):-1000, 14, 15};
Plane Surface(1) = {1};

// Cylinder: the arc from the contact to the ends of the diameter, and the diameter y = R.
Point(21) = {R, R, 0, lc}; Point(23) = {-R, R, 0, lc};
Circle(21) = {2000 + n, 3, 21}; Line(22) = {21, 3}; Line(23) = {3, 23};
Circle(24) = {23, 3, 2000};
Curve Loop(2) = {2000:2000 + n - 1, 21, 22, 23, 24};
Plane Surface(2) = {2};

// Size: hc within w of the origin, growing by `growth` per unit distance beyond (at most lc).
// gmsh multiplies the field by the size factor f (-clscale); hc is divided by it so that the
// elements near the contact match the contact faces' (2w/n, set by n alone), while the growth
// rate and the far size scale with f: n = 96 with f = 0.5 halves every element of n = 48.
f = Mesh.MeshSizeFactor;
Field[1] = Distance; Field[1].PointsList = {1000 + n / 2, 2000 + n / 2};
Field[2] = MathEval;
Field[2].F = Sprintf("Min(%g, %g + %g * Max(F1 - %g, 0))", lc, hc / f, growth, w);
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("block") = {1};
Physical Surface("cylinder") = {2};
Physical Curve("flat") = {1000:1000 + n - 1};
Physical Curve("arc") = {2000:2000 + n - 1};
Physical Curve("bottom") = {11};
Physical Curve("top_right") = {22};
Physical Curve("top_left") = {23};
Physical Curve("top") = {22, 23};
