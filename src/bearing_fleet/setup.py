from setuptools import setup

PACKAGE = "bearing_fleet"

setup(
    name=PACKAGE,
    version="0.2.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description="One view of a fleet of monitored motors: the fleet node (fleet_state) and bearing-fleet.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "fleet = bearing_fleet.executables:fleet",
            "bearing-fleet = bearing_fleet.fleet_cli:main",
        ],
    },
)
