"""Numbers printed in the two papers, as data (SI units unless the name says).

Angeles, Alivizatos, Zsombor-Murray, "The Synthesis of Smooth Trajectories for
Pick-and-Place Operations", IEEE Trans. SMC, 1988, Section V:

* Table II: the 7-number poses of the pick and the place (printed to two
  decimals; positions in mm there, metres here);
* Table III: the joint coordinates the authors' KINVERS package returned for
  them (degrees there and in the ``_DEG`` names here).

Kang, "Online Trajectory Planning for a PUMA Robot", IJPEM, 2007, Section 3:
the elbow-singular values of θ3 for d4 = 0.4318 m and a3 = 0.0203 m.
"""

from __future__ import annotations

import numpy as np

#: Angeles Table III, pick configuration [deg].
ANGELES_PICK_Q_DEG = np.array([0.0, 45.0, 200.0, -100.0, 30.0, 10.0])
#: Angeles Table III, place configuration [deg].
ANGELES_PLACE_Q_DEG = np.array([150.0, -100.0, -10.0, 100.0, -70.0, 170.0])

#: Angeles Table II, pick pose as angeles7 [e sinφ (3), cosφ, p (3) in m].
ANGELES_PICK_ANGELES7 = np.array(
    [0.68, -0.49, -0.19, -0.52, -0.09407, 0.12540, -0.47055]
)
#: Angeles Table II, place pose as angeles7 [e sinφ (3), cosφ, p (3) in m].
ANGELES_PLACE_ANGELES7 = np.array([0.18, 0.29, 0.33, -0.88, 0.35928, -0.35223, 0.29546])

#: Printed precision of Table II: orientation numbers to 0.01, positions to 0.01 mm.
ANGELES_TABLE2_HALF_ULP = np.array([0.005] * 4 + [0.005e-3] * 3)

#: Angeles' trajectory duration in Section V [s].
ANGELES_DURATION = 10.0

#: Kang Sec. 3: elbow-singular θ3 [deg] for d4 = 0.4318 m, a3 = 0.0203 m.
KANG_ELBOW_THETA3_DEG = (87.308, -92.692)
