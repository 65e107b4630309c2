# Sources of the geometry module.
