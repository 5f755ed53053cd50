// A block pressed onto and pushed along a base of the same width (plane strain benchmark of
// the frictional, unsymmetric tangent). Coincident but distinct nodes on y = H.
// Physical groups: surfaces "base", "block"; curves "ground", "base_top", "block_bottom",
// "block_top".
DefineConstant[ L = {100, Name "width L [mm]"} ];
DefineConstant[ H = {50, Name "base height H [mm]"} ];
DefineConstant[ h = {25, Name "block height h [mm]"} ];
DefineConstant[ n = {40, Name "elements across the width"} ];
Geometry.AutoCoherence = 0;
Point(1) = {0, 0, 0}; Point(2) = {L, 0, 0}; Point(3) = {L, H, 0}; Point(4) = {0, H, 0};
Point(5) = {0, H, 0}; Point(6) = {L, H, 0}; Point(7) = {L, H + h, 0}; Point(8) = {0, H + h, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
Transfinite Curve{1, 3, 5, 7} = n + 1;
Transfinite Curve{2, 4} = Ceil(n * H / L) + 1;
Transfinite Curve{6, 8} = Ceil(n * h / L) + 1;
Transfinite Surface{1, 2};
Recombine Surface{1, 2};
Physical Surface("base") = {1};
Physical Surface("block") = {2};
Physical Curve("ground") = {1};
Physical Curve("base_top") = {3};
Physical Curve("block_bottom") = {5};
Physical Curve("block_top") = {7};
