"""Dataset sources: loaders of the official layouts (HumanML3D, KIT, HumanAct12, UESTC) and raw mocap (Bandai)."""
