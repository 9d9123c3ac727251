(cnc-gym example: drill.nc - four holes 10 mm deep peck-drilled with G83, two spot holes with G81)
(GSK 25i. G54 at the plate's lower left corner, top face Z0. G99 returns to the R level)
(between holes, G98 to the initial level Z10 after the last hole of each cycle.)
O0003
G90 G54 G17 G21
S3000 M03
G00 X0. Y0. Z10.
G99 G83 X10. Y10. Z-10. R2. Q3. F200.
X30.
Y30.
G98 X10.
G80
G99 G81 X20. Y20. Z-1. R2. F150.
G98 Y40.
G80
G00 Z20.
M05
M30
