%
(NAM,BORE7)
(UTL,1)
(UCY,60)
! Probe the part on KT01 (App. E probe cycles, shipped as KT-APL source):
! the top face with G26Z, the bore with G27X and G27Y, into the inspection
! file INSP7 (G36 + OIF ... G37, manual ch. 7), copied to HOST by RCP
! (not named as the program: the copy would replace it in HOST); the
! measured centre becomes fixture offset H1 (FXC), as FINDBORE does (9-10).
N10 G71 G90 G0 X150. Y100. Z40. F0 T1
N20 M06
N22 Z40. ! the probe's length applies from the next Z move
N25 (PAR,L1003=3.,L1004=3.) ! the 6 mm ball's effective radius
N30 G36
N40 (OIF,INSP7)
N50 G26Z-20.
N60 G0 X200. Y100. Z40.
N70 Z0.
N80 G27X220.
N90 G27Y120.
N100 (PAR,L1=X-200.,L2=Y-100.)
N110 (FXC,H1XL1YL2)
N120 G0 Z40.
N130 G37
N140 (RCP,INSP7,TO,HOST,INSP7)
N150 M30
%
