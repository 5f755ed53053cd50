// Square block on a rigid base under top pressure (plane strain benchmark model).
// Structured n x n quad8 mesh: about 6 n² unknowns (n = 41: 10k, 129: 100k, 408: 1M).
// Physical groups: surface "block"; curves "bottom" (y = 0), "left" (x = 0), "top" (y = L).
DefineConstant[ L = {100, Name "edge length L [mm]"} ];
DefineConstant[ n = {40, Name "elements per edge"} ];
Point(1) = {0, 0, 0};
Point(2) = {L, 0, 0};
Point(3) = {L, L, 0};
Point(4) = {0, L, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = n + 1;
Transfinite Surface{1};
Recombine Surface{1};
Physical Surface("block") = {1};
Physical Curve("bottom") = {1};
Physical Curve("left") = {4};
Physical Curve("top") = {3};
