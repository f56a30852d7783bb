"""Sample preparation: raining grains into a chamber, dropping a weight, relaxing."""
