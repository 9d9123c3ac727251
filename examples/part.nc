(cnc-gym example: part.nc - the outline of a 40 x 30 mm plate with two R10 corners)
(GSK 25i. G54 at the plate's lower left corner, top face Z0. The programmed path is the)
(tool centre: no cutter compensation, to keep the example short.)
O0001
G90 G54 G17 G21
S6000 M03
G00 X-5. Y0. Z5.
G01 Z-2. F400.
G01 X30. F1500.
G03 X40. Y10. R10.
G01 Y30.
G01 X10.
G03 X0. Y20. R10.
G01 Y-5.
G00 Z5.
M05
M30
