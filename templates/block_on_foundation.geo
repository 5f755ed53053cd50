// A block pressed onto a wider foundation, plane strain, half model (x = 0 is a symmetry
// plane). Written by `asperity init`; run it with `asperity run case.toml`.
//
// The contact between the block and the foundation can be defined in two ways:
// recipe = 0: two bodies meshed separately, with distinct nodes at the same coordinates along
//             y = 0 (curves "foundation_top" and "block_bottom"; Geometry.AutoCoherence = 0
//             keeps gmsh from merging them). Case: [[contact]] side_a / side_b.
// recipe = 1: one conforming mesh whose shared curve "contact" asperity splits into
//             interface elements. Case: [[contact]] curve / body_a / body_b.
// Physical groups: surfaces "foundation", "block"; curves "base" (y = -H), "symmetry"
// (x = 0, both bodies), "top" (y = h) and the contact curves above.
// The mesh size factor (`[mesh] size`, gmsh -clscale) scales the element counts.
DefineConstant[ w = {10, Name "block half-width w [mm]"} ];
DefineConstant[ h = {10, Name "block height h [mm]"} ];
DefineConstant[ W = {30, Name "foundation half-width W [mm]"} ];
DefineConstant[ H = {20, Name "foundation depth H [mm]"} ];
DefineConstant[ n = {8, Name "elements along the contact (size factor 1)"} ];
DefineConstant[ recipe = {0, Choices {0 = "two coincident curves", 1 = "one curve, split"}, Name "contact definition"} ];

s = Mesh.MeshSizeFactor;
nc = Ceil(n / s);               // elements along the contact
no = Ceil(nc * (W - w) / w);    // along the free part of the foundation's top
nh = Ceil(nc * h / w);          // through the block
nd = Ceil(nc * H / w);          // through the foundation
Mesh.MeshSizeFactor = 1;        // the counts above already carry the size factor
Geometry.AutoCoherence = (recipe == 1);

// Foundation (body A): 0 <= x <= W, -H <= y <= 0.
Point(1) = {0, -H, 0}; Point(2) = {W, -H, 0}; Point(3) = {W, 0, 0};
Point(4) = {w, 0, 0};  Point(5) = {0, 0, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4, 5}; Plane Surface(1) = {1};

// Block (body B): 0 <= x <= w, 0 <= y <= h.
Point(6) = {w, h, 0}; Point(7) = {0, h, 0};
If (recipe == 1)
  // The block's bottom is the foundation's line 4: one conforming curve.
  Line(6) = {4, 6}; Line(7) = {6, 7}; Line(8) = {7, 5};
  Curve Loop(2) = {-4, 6, 7, 8}; Plane Surface(2) = {2};
  block_bottom = 4;
  Physical Curve("contact") = {4};
Else
  // Its own bottom line on points of its own at the same coordinates.
  Point(8) = {0, 0, 0}; Point(9) = {w, 0, 0};
  Line(9) = {8, 9}; Line(6) = {9, 6}; Line(7) = {6, 7}; Line(8) = {7, 8};
  Curve Loop(2) = {9, 6, 7, 8}; Plane Surface(2) = {2};
  block_bottom = 9;
  Physical Curve("foundation_top") = {4};
  Physical Curve("block_bottom") = {9};
EndIf

Transfinite Curve{4, 7, block_bottom} = nc + 1;
Transfinite Curve{3} = no + 1;
Transfinite Curve{1} = nc + no + 1;
Transfinite Curve{2, 5} = nd + 1;
Transfinite Curve{6, 8} = nh + 1;
Transfinite Surface{1} = {1, 2, 3, 5};
Transfinite Surface{2};
Recombine Surface{1, 2};

Physical Surface("foundation") = {1};
Physical Surface("block") = {2};
Physical Curve("base") = {1};
Physical Curve("symmetry") = {5, 8};
Physical Curve("top") = {7};
