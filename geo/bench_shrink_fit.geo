// Benchmark against CalculiX (benches/calculix): shrink fit of a solid shaft (0 <= r <= b)
// in a hub (b <= r <= c), axisymmetric slice of height L (x = r, y = z); the geometry of
// examples/shrink_fit/shrink_fit.geo (recipe 0: coincident but distinct nodes on r = b), kept separate so
// that the benchmark does not change when the example does.
// Physical groups: surfaces "shaft", "hub"; curves "shaft_ends", "hub_ends", "hub_outer",
// "shaft_outer" (contact side A), "hub_bore" (contact side B); point "probe" = (c, 0), where
// the benchmark compares the radial displacement.
// Size: about 12 n^2 / s^2 unknowns for b = L, c = 2b (s = -clscale).
DefineConstant[ b = {10, Name "interface radius b [mm]"} ];
DefineConstant[ c = {20, Name "hub outer radius c [mm]"} ];
DefineConstant[ L = {10, Name "slice height L [mm]"} ];
DefineConstant[ n = {6, Name "elements through each wall (size factor 1)"} ];

s = Mesh.MeshSizeFactor;
nw = Ceil(n / s);
nz = Ceil(nw * L / b);
Mesh.MeshSizeFactor = 1;
Geometry.AutoCoherence = 0;

Point(1) = {0, 0, 0};  Point(2) = {b, 0, 0};  Point(3) = {b, L, 0};  Point(4) = {0, L, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Point(5) = {b, 0, 0}; Point(6) = {c, 0, 0}; Point(7) = {c, L, 0}; Point(8) = {b, L, 0};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
Transfinite Curve{1, 3, 5, 7} = nw + 1;
Transfinite Curve{2, 4, 6, 8} = nz + 1;
Transfinite Surface{1, 2};
Recombine Surface{1, 2};

Physical Surface("shaft") = {1};
Physical Surface("hub") = {2};
Physical Curve("shaft_ends") = {1, 3};
Physical Curve("hub_ends") = {5, 7};
Physical Curve("hub_outer") = {6};
Physical Curve("shaft_outer") = {2};
Physical Curve("hub_bore") = {8};
Physical Point("probe") = {6};
