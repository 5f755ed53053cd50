// Shrink fit: solid shaft (0 <= r <= b) in a hub (b <= r <= c), axisymmetric slice of
// height L (x = r, y = z). Validation case of docs/theory.md, "Lamé cylinders and the shrink
// fit": with u_z = 0 on the end planes of both bodies the contact pressure is
// p = delta / (C + 1/k_N).
//
// recipe = 0: two bodies with coincident but distinct nodes on r = b (curves "shaft_outer"
//             and "hub_bore"; case: side_a/side_b).
// recipe = 1: one conforming mesh whose shared curve "fit" is split by asperity
//             (case: curve/body_a/body_b).
// Physical groups: surfaces "shaft", "hub"; curves "shaft_ends", "hub_ends", "hub_outer",
// and the contact curves above.
// Run: gmsh shrink_fit.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1
//      [-setnumber b 10 -setnumber c 20 -setnumber L 10 -setnumber n 6 -setnumber recipe 0]
DefineConstant[ b = {10, Name "interface radius b [mm]"} ];
DefineConstant[ c = {20, Name "hub outer radius c [mm]"} ];
DefineConstant[ L = {10, Name "slice height L [mm]"} ];
DefineConstant[ n = {6, Name "elements through each wall (size factor 1)"} ];
DefineConstant[ recipe = {0, Choices {0 = "coincident nodes", 1 = "conforming, split"}, Name "mesh recipe"} ];

s = Mesh.MeshSizeFactor;
nw = Ceil(n / s);
nz = Ceil(nw * L / b);
Mesh.MeshSizeFactor = 1;
Geometry.AutoCoherence = (recipe == 1);

Point(1) = {0, 0, 0};  Point(2) = {b, 0, 0};  Point(3) = {b, L, 0};  Point(4) = {0, L, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
If (recipe == 1)
  Point(6) = {c, 0, 0}; Point(7) = {c, L, 0};
  Line(5) = {2, 6}; Line(6) = {6, 7}; Line(7) = {7, 3};
  Curve Loop(2) = {5, 6, 7, -2}; Plane Surface(2) = {2};
  Physical Curve("fit") = {2};
  hub_ends[] = {5, 7}; hub_outer = 6; hub_bore = 2;
Else
  Point(5) = {b, 0, 0}; Point(6) = {c, 0, 0}; Point(7) = {c, L, 0}; Point(8) = {b, L, 0};
  Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
  Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
  Physical Curve("shaft_outer") = {2};
  Physical Curve("hub_bore") = {8};
  hub_ends[] = {5, 7}; hub_outer = 6; hub_bore = 8;
EndIf
Transfinite Curve{1, 3, 5, 7} = nw + 1;
Transfinite Curve{2, 4, 6, hub_bore} = nz + 1;
Transfinite Surface{1, 2};
Recombine Surface{1, 2};

Physical Surface("shaft") = {1};
Physical Surface("hub") = {2};
Physical Curve("shaft_ends") = {1, 3};
Physical Curve("hub_ends") = {hub_ends[]};
Physical Curve("hub_outer") = {hub_outer};
// The bottom end planes alone (z = 0), for a slice free to expand axially.
Physical Curve("shaft_bottom") = {1};
Physical Curve("hub_bottom") = {5};
