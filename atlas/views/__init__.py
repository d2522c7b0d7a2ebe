"""Views read files and draw: plots, the interactive page, text reports. They compute no labels."""
