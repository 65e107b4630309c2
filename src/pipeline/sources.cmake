# Sources of the pipeline module.
