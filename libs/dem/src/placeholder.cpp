// replaced by the DEM sources
