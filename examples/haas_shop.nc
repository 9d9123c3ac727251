%
O02024 (BRACKET OP1 - HAAS STYLE, WRITTEN FOR CNC-GYM)
(cnc-gym example: a shop program in the style of a Haas mill, mm, with the operator's tables in)
(examples/shop_setup.yaml: G54 at the vise jaw, T1 12 mm end mill H1/D1, T2 spot drill H2, T3 engraver H3.)
(cnc-gym trace examples/haas_shop.nc --dialect fanuc --setup examples/shop_setup.yaml)
G00 G17 G21 G40 G49 G80 G90
G91 G28 Z0.
G90
(T1 - CONTOUR WITH CUTTER COMPENSATION)
T1 M06
IF [#5401 GE 3600.] THEN #3000= 1 (TOOL 1 LIFE EXPIRED)
G54 G00 X-20. Y-10. S3000 M03
G43 H01 Z10. M88
G01 Z-2. F300.
#1=0
WH [#1 LT 2] DO1
G41 D01 G01 X0. Y0. F600.
Y40.
X60.
G02 X70. Y30. R10.
G01 Y0.
X-10.
G40 G01 X-20. Y-10.
#1=#1+1
Z[-2.-2.*#1]
EN1
G00 Z10. M89
(T2 - SPOT DRILL, HAAS CYCLE WITHOUT R, L REPEATS)
T2 M06
G54 G00 X10. Y10. S2500 M03
G43 H02 Z5. M08
G91 G82 X10. Z-3. P0.5 F200. L4
G90 G80 G00 Z10. M09
(T3 - ENGRAVE THE PART NUMBER)
T3 M06
G54 G00 X10. Y45. S8000 M03
G43 H03 Z5.
G47 P0 (BK-2024) X10. Y45. I0. J4. R1. Z-0.2 F300. E100.
G00 Z10. M05
G91 G28 Z0.
G90 G53 Y0.
M30
%
