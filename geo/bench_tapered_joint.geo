// Benchmark against CalculiX (benches/calculix): tapered (conical) press fit, axisymmetric
// (x = r, y = z); the geometry of examples/tapered_joint/tapered_joint.geo (paper §4.2), kept separate so that
// the benchmark does not change when the example does. The shaft is pushed into the sleeve by
// a pressure on its top face; the sleeve rests on its bottom face.
// Two bodies with coincident but distinct nodes on the cone (Geometry.AutoCoherence = 0).
// Physical groups: surfaces "shaft", "sleeve"; curves "shaft_cone" (contact side A),
// "sleeve_cone" (side B), "shaft_top" (load), "sleeve_bottom" (support), "shaft_bottom",
// "sleeve_outer", "sleeve_top"; point "top_centre" = (0, L + L_head), where the benchmark
// compares the axial displacement.
// Size: about 1 600 / s^2 unknowns with the defaults (s = -clscale).
DefineConstant[ taper = {0.2, Name "tan(gamma): half-angle tangent of the cone (DIN 1:2.5)"} ];
DefineConstant[ L = {40, Name "contact length L [mm]"} ];
DefineConstant[ r_m = {20, Name "mean contact radius r_m [mm]"} ];
DefineConstant[ R_o = {40, Name "sleeve outer radius R_o [mm]"} ];
DefineConstant[ L_head = {20, Name "height of the shaft head above the sleeve [mm]"} ];
DefineConstant[ n_cone = {16, Name "elements along the cone (size factor 1)"} ];
DefineConstant[ n_radial = {6, Name "elements across shaft and sleeve (size factor 1)"} ];

s = Mesh.MeshSizeFactor;
nc = Ceil(n_cone / s);
nr = Ceil(n_radial / s);
nh = Ceil(nc * L_head / L);
Mesh.MeshSizeFactor = 1;
Geometry.AutoCoherence = 0;

r0 = r_m - 0.5 * L * taper;
r1 = r_m + 0.5 * L * taper;

Point(1) = {0, 0, 0}; Point(2) = {r0, 0, 0}; Point(3) = {r1, L, 0}; Point(4) = {0, L, 0};
Point(5) = {r1, L + L_head, 0}; Point(6) = {0, L + L_head, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, -3}; Plane Surface(2) = {2};

Point(11) = {r0, 0, 0}; Point(12) = {R_o, 0, 0}; Point(13) = {R_o, L, 0}; Point(14) = {r1, L, 0};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(3) = {11, 12, 13, 14}; Plane Surface(3) = {3};

Transfinite Curve{1, 3, 6} = nr + 1;
Transfinite Curve{11, 13} = nr + 1;
Transfinite Curve{2, 4, 12, 14} = nc + 1;
Transfinite Curve{5, 7} = nh + 1;
Transfinite Surface{1, 2, 3};
Recombine Surface{1, 2, 3};

Physical Surface("shaft") = {1, 2};
Physical Surface("sleeve") = {3};
Physical Curve("shaft_cone") = {2};
Physical Curve("sleeve_cone") = {14};
Physical Curve("shaft_top") = {6};
Physical Curve("shaft_bottom") = {1};
Physical Curve("sleeve_bottom") = {11};
Physical Curve("sleeve_outer") = {12};
Physical Curve("sleeve_top") = {13};
Physical Point("top_centre") = {6};
