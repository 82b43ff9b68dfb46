"""conesim envs package."""
