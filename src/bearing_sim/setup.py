from setuptools import setup

PACKAGE = "bearing_sim"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description=("29-degree-of-freedom rotor/bearing/housing simulator (thesis ch. 2, app. A) with outer- and "
                 "inner-race defects; simulator node and bearing-sim CLI."),
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            'simulator = bearing_sim.executables:simulator',
            'bearing-sim = bearing_sim.sim_cli:main',
        ],
    },
)
