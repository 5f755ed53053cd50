// Thick-walled cylinder under internal pressure, axisymmetric (x = r, y = z).
// A slice of height H of a cylinder with bore radius a and outer radius b; with
// u_z = 0 on both end planes it is the plane-strain Lamé problem
// (docs/theory.md, "Lamé cylinders and the shrink fit").
//
// Physical groups: surface "cylinder"; curves "bore" (r = a, pressure), "outer" (r = b),
// "bottom" (z = 0) and "top" (z = H); point "bore_point" (r = a, z = 0).
// Run: gmsh thick_cylinder_axi.geo -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1
//      [-setnumber a 10 -setnumber b 20 -setnumber H 5 -setnumber n_wall 4 -clscale 1]
DefineConstant[ a = {10, Name "bore radius a [mm]"} ];
DefineConstant[ b = {20, Name "outer radius b [mm]"} ];
DefineConstant[ H = {5, Name "slice height H [mm]"} ];
DefineConstant[ n_wall = {4, Name "elements through the wall (at size factor 1)"} ];

// Elements through the wall scale with the size factor: -clscale s gives about n_wall / s.
s = Mesh.MeshSizeFactor;
nw = Ceil(n_wall / s);
nh = Ceil(nw * H / (b - a));
Mesh.MeshSizeFactor = 1;

Point(1) = {a, 0, 0};
Point(2) = {b, 0, 0};
Point(3) = {b, H, 0};
Point(4) = {a, H, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nw + 1;
Transfinite Curve{2, 4} = nh + 1;
Transfinite Surface{1};
Recombine Surface{1};

Physical Surface("cylinder") = {1};
Physical Curve("bore") = {4};
Physical Curve("outer") = {2};
Physical Curve("bottom") = {1};
Physical Curve("top") = {3};
// A point on the bore at z = 0 (e.g. for the bore displacement in convergence studies).
Physical Point("bore_point") = {1};
