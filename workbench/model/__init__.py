"""Robot models: DH tables, URDF generation, the robot catalog, loading, Robot."""
