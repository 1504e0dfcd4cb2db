"""Grasps on labelled meshes: a parallel-jaw gripper, antipodal sampling with a parallel gradient-based local
search (DiPGrasp-style), the Ferrari-Canny quality, and a physics lift test (conventions §6, the paper's Table 3)."""
