// Machine-tool slideway joint (plane strain): a carriage (60 x 20 mm) pressed on a guide
// (60 x 30 mm), their faces coincident at y = 0 with distinct nodes (the joint).
// Physical groups: surfaces "guide", "carriage"; curves "guide_bottom", "guide_top",
// "guide_left", "carriage_bottom", "carriage_top", "carriage_left", "carriage_right",
// "guide_right".
DefineConstant[ w = {60, Name "width [mm]"} ];
DefineConstant[ hg = {30, Name "guide height [mm]"} ];
DefineConstant[ hc = {20, Name "carriage height [mm]"} ];
DefineConstant[ n = {24, Name "elements across the width (size factor 1)"} ];
// The mesh size factor ([mesh] size, gmsh -clscale) divides the element counts.
nx = Ceil(n / Mesh.MeshSizeFactor);
Mesh.MeshSizeFactor = 1;
Point(1) = {0, -hg, 0};
Point(2) = {w, -hg, 0};
Point(3) = {w, 0, 0};
Point(4) = {0, 0, 0};
Point(5) = {0, 0, 0};
Point(6) = {w, 0, 0};
Point(7) = {w, hc, 0};
Point(8) = {0, hc, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2};
Transfinite Curve{1, 3, 5, 7} = nx + 1;
Transfinite Curve{2, 4} = Round(nx * hg / w) + 1;
Transfinite Curve{6, 8} = Round(nx * hc / w) + 1;
Transfinite Surface{1};
Transfinite Surface{2};
Recombine Surface{1, 2};
Physical Surface("guide") = {1};
Physical Surface("carriage") = {2};
Physical Curve("guide_bottom") = {1};
Physical Curve("guide_right") = {2};
Physical Curve("guide_top") = {3};
Physical Curve("guide_left") = {4};
Physical Curve("carriage_bottom") = {5};
Physical Curve("carriage_right") = {6};
Physical Curve("carriage_top") = {7};
Physical Curve("carriage_left") = {8};
