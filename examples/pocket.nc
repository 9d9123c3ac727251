(cnc-gym example: pocket.nc - a 30 x 20 mm pocket with R6 corners, 2 mm deep in two 1 mm steps)
(GSK 25i. G54 at the pocket's centre, top face Z0, 6 mm end mill; the programmed path is the)
(tool centre. Subprogram O0100 clears one level: a roughing lap, then the finishing lap.)
O0002
G90 G54 G17 G21
S8000 M03
G00 X0. Y0. Z5.
G00 Z1.
G01 Z-1. F300.
M98 P0100
G01 Z-2. F300.
M98 P0100
G00 Z5.
M05
M30

O0100
(roughing lap 14 x 4 mm about the centre, step-over 5 mm to the finishing lap)
G01 X7. Y0. F1200.
G01 Y2.
G01 X-7.
G01 Y-2.
G01 X7.
G01 Y0.
(finishing lap 24 x 14 mm, R3 tool-centre corners, climb milling)
G01 X12.
G01 Y4.
G03 X9. Y7. R3.
G01 X-9.
G03 X-12. Y4. R3.
G01 Y-4.
G03 X-9. Y-7. R3.
G01 X9.
G03 X12. Y-4. R3.
G01 Y0.
G01 X0.
M99
