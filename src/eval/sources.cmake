# Sources of the eval module.
