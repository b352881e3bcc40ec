"""Decision layer: release logic and the detector pipeline shared by the node and the tools."""
