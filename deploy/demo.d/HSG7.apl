%
(NAM,HSG7)
(UTL,7777)
(UCY,45)
! Gear housing: needs face mill 7777, which no station holds until loaded.
N10 G71 G90 G01
N20 T7777 M06
N30 X0 Y0 Z50. F0
N40 Z2. F1000.
N50 X160. Y0 F1500.
N60 G00 Z50. F0
N70 M30
%
